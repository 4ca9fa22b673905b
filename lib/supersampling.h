/// @file supersampling.h
/// @brief Sub-pixel samples (docs/equations.md#sub-pixel-samples): the resolution a fog volume's
///        frame needs where its voxels look small, and the box filter back to the image's.
///        A camera averages transmittance over a pixel; a footprint a pixel wide averages
///        optical depth, and exp(-mean tau) <= mean exp(-tau) (Jensen): voxels smaller than a
///        pixel render too opaque and too bright unless each pixel is cut into sub-pixels that
///        the voxels span.
#pragma once

#include <vdb_ewa/camera.h>
#include <vdb_ewa/frame.h>
#include <vdb_ewa/render_settings.h>

#include "source/source.h"
#include "support/memory_budget.h"

#include <string>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// The sub-pixel samples of a frame: the window of pixels [x0, x0 + width) x [y0, y0 + height)
/// that the volume can reach, composited at factor x factor sub-pixels a pixel; the rest of
/// the image is empty. factor 1: the frame as it is, the window the whole image.
struct Supersampling
{
    int factor = 1;
    int x0 = 0, y0 = 0, width = 0, height = 0;
    /// The active voxels' median screen size in pixels (+inf: unmeasured, e.g. no leaf nodes).
    double voxelPixels = 0;
    /// Where the voxels span between 3/4 of supersampleSpan and all of it, the frame at one
    /// sample a pixel is rendered too and mixed in with this weight, rising from 0 to 1 across
    /// that range: going from 2 x 2 sub-pixels to one sample a pixel changed pyro's image by up
    /// to 0.26 in a pixel between two camera positions 1e-4 apart (popping in a fly-in).
    double blend = 0.0;
    /// True where the factor was lowered so that active tiles' kernels stay within
    /// tileKernelBudget.
    bool tileLimited = false;
};

/// The last quarter of the span below supersampleSpan, over which a factor of 2 fades into one
/// sample a pixel (Supersampling::blend).
inline constexpr double kBlendShare = 0.25;

/// Sub-pixels a pixel side at most, over all the frame's (16 images' worth, and at least 2^22):
/// what one supersampled frame may take in time and memory before the factor is lowered.
double supersampledPixelBudget(int width, int height);

/// Kernels of active tiles larger than a leaf node that sub-pixels may make, at most (their
/// lattices follow the sub-pixels): 32 a pixel of the @a width x @a height image, between 2^16
/// and 2^21.
double tileKernelBudget(int width, int height);

/// The median over the active voxels of their screen size in pixels (LevelOfDetail::voxelPixels
/// of each leaf node and each active tile, weighted by its active voxels; +inf where there are
/// none, or where the median node reaches the near plane).
double medianVoxelPixels(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings);

/// The screen size in pixels of the voxels in view, at @a quantile of them (0.5: the median),
/// each leaf node (the box of its active voxels) and each active tile weighted by its active
/// voxels and sized at its box's centre (its longest index axis over that centre's depth);
/// boxes whose centre lies before the near plane or whose bounding sphere misses the frame
/// are left out; +inf where none is in view. With emission or temperature grids, the smallest
/// of their measures and the density's.
/// Where medianVoxelPixels takes a node reaching the near plane as infinitely large (the level
/// of detail's safe side), this measures what the frame shows (--pixel-size).
double voxelPixelsInView(const GridSource::Impl& grid, const Camera& camera, double quantile);

/// The pixels of @a camera's image that the volume's splats can reach: its active box (and its
/// emission grids'), padded by the widest kernel's reach and motion blur's largest travel,
/// projected, widened by the low-pass filter's and the lens's reach; the whole image where the
/// box reaches the near plane or the grid is not affine. Empty (width 0) where no part is seen.
Supersampling reachedWindow(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings);

/// The sub-pixel samples for @a camera: S = ceil(supersampleSpan / median voxel pixels) in
/// [1, supersample], lowered to fit supersampledPixelBudget and half the memory @a budget
/// (a warning line then, in @a warnings), and so that active tiles larger than a leaf node,
/// whose lattices follow the sub-pixels, make at most tileKernelBudget kernels (no warning: a
/// designed bound); 1 for a @a passes.deep image (warned where the voxels asked for more), and
/// where the window is empty.
Supersampling chooseSupersampling(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings,
    const PassRequest& passes, const MemoryBudget& budget, std::vector<std::string>& warnings);

/// @a frame times 1 - @a weight plus @a other times @a weight: colour, alpha, transmittance and
/// the colour passes; Z, the one of the larger weight.
void mixFrames(Frame& frame, const Frame& other, double weight);

/// @a sub, rendered through camera.window(s.x0, s.y0, s.width, s.height, s.factor), brought
/// back to the @a width x @a height image: colour, alpha, transmittance and the colour passes
/// averaged over each pixel's sub-pixels (a box filter: the camera's pixel); Z, where alpha
/// reaches 0.5, the median of the sub-pixels' (inf where half of them never reach it);
/// outside the window, the empty image's values.
Frame boxFiltered(const Frame& sub, const Supersampling& s, int width, int height, const PassRequest& passes);

} // namespace detail
} // namespace vdb_ewa
