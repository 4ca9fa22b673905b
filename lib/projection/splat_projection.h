/// @file splat_projection.h
/// @brief Kernels -> screen-space splats: footprint (Eq. 29-33), slab shares, colour.
#pragma once

#include "source/source.h"
#include "support/rgb.h"

#include <vdb_ewa/camera.h>
#include <vdb_ewa/ewa_kernel.h>
#include <vdb_ewa/frame.h>
#include <vdb_ewa/slab_share.h>

#include <cstdint>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// A kernel ready to rasterise: optical depth tau_c(p) = tau[c] * exp(-0.5 d^T Q d) * share_s,
/// emission E_c(p) = emission[c] * exp(-0.5 d^T Q d) * share_s in slab s, and the scattering
/// weight scatter[c] likewise, which the compositor lights at each slab sample (light map).
struct Splat
{
    float cx, cy;              ///< centre, raster
    float qa, qb, qc;          ///< conic Q = [qa qb; qb qc], 1/pixels^2
    float cutoff;              ///< evaluate where d^T Q d < cutoff (= cutoffRadius^2)
    float tau[3];              ///< peak optical depth per channel
    float emission[3];         ///< peak optical depth x source colour already shaded (self-emission, surfaces)
    float scatter[3];          ///< peak optical depth x material colour: lit per slab sample
    int x0, y0, x1, y1;        ///< inclusive pixel box, clipped to the image
    std::int64_t firstSlab;    ///< first slab it overlaps
    std::uint64_t shareOffset; ///< index of its first slab share in SplatSet::shares
    std::uint32_t slabCount;   ///< number of slabs it overlaps
    /// Motion blur's shutter layers it darkens (KernelMotion::layerFirst, layerCount; 0 of
    /// them: all).
    std::uint16_t layerFirst, layerCount;
};
static_assert(sizeof(Splat) == 104, "Splat: the shutter layers fill the padding after slabCount");

/// The layout of the passes beside the beauty that have source terms of their own: the shadow
/// pass first, then the emission pass, each only if asked for. SplatSet::passSources holds a
/// splat's terms in this order, and the slab compositor its pass planes.
struct PassLayout
{
    int shadow = -1, emission = -1; ///< index of each pass, -1 if not asked for
    int count = 0;

    PassLayout() = default;
    explicit PassLayout(const PassRequest& passes)
    {
        if (passes.shadow) shadow = count++;
        if (passes.emission) emission = count++;
    }
};

struct SplatSet
{
    LargeArray<Splat> splats; ///< in kernel order (deterministic)
    LargeArray<float> shares; ///< slab shares of all splats
    /// Where each share's mass lies in its slab: the mean and mean square of its position,
    /// 0 at the slab's front and 1 at its back; two floats per share.
    LargeArray<float> shareMoments;
    SlabGrid slabs;
    std::uint64_t culled = 0;     ///< outside the frustum or behind the eye
    std::uint64_t beforeNear = 0; ///< centre before the near plane: dropped
    std::uint64_t clampedNear = 0;    ///< within 3 sigma of the eye: J formed at 3 sigma
    std::uint64_t clampedGrazing = 0; ///< beyond 1.3 x the frustum edge: J formed at the edge
    std::uint64_t clippedSpan = 0; ///< kernels spanning more slabs than kMaxSlabSpan
    double requestedThickness = 0; ///< > 0 if the slab thickness was raised from this value
    /// Extra source terms for the shadow and emission passes, like Splat::emission (peak
    /// optical depth x source colour), passSourceCount x RGB per splat, in splat order.
    int passSourceCount = 0;
    LargeArray<float> passSources;
    /// Motion blur: each splat's move from where its material is in the still field (world,
    /// KernelMotion::shift), 3 floats per splat in splat order; empty: none moved. The
    /// compositor looks each slab sample's light up where its material came from.
    LargeArray<float> shifts;
};

/// Kernels end at +-3 standard deviations along the ray (99.73 %).
constexpr double kDepthTruncation = 3.0;
/// Most slabs one kernel may span; shares past it are dropped (counted in clippedSpan).
constexpr int kMaxSlabSpan = 1024;
/// The slab thickness is raised so that no kernel spans more than this many slabs.
constexpr int kSlabSpanTarget = 256;

/// The footprint parameters of @a camera and @a splat (the frustum-edge clamp at 1.3x).
ProjectionParams projectionParams(const Camera& camera, const SplatOptions& splat);

/// The inclusive box of pixels whose centres lie in @a fp's cut-off box, clipped to the image;
/// false if empty.
bool pixelBox(const Footprint& fp, int width, int height, int& x0, int& y0, int& x1, int& y1);

/// Copy @a fp's centre and conic, and the cut-off radius^2, into a splat (Splat, SurfaceSplat).
template <typename S>
void setFootprint(S& s, const Footprint& fp, double cutoffRadius)
{
    s.cx = float(fp.centre.x);
    s.cy = float(fp.centre.y);
    s.qa = float(fp.conic.xx);
    s.qb = float(fp.conic.xy);
    s.qc = float(fp.conic.yy);
    s.cutoff = float(cutoffRadius * cutoffRadius);
}

/// Project every kernel through @a camera (one task per block of kernels).
/// @a colors: each kernel's material colour, multiplied into the scattering weight (empty:
/// white); the light's transmittance is applied by the compositor per slab sample. @a passes:
/// the emission pass adds its source term to SplatSet::passSources (the shadow pass is lit per
/// slab sample too). @a progress: one unit per kernel; throws Cancelled. @a slabs: the slabs to
/// use (a streamed frame's windows share them); null: frameSlabs, raised where a kernel would
/// span more than kSlabSpanTarget of them.
SplatSet projectSplats(const GridSource::Impl& grid, const KernelSet& kernels, const std::vector<Rgb>& colors,
    const Camera& camera, const RenderSettings& settings, const PassRequest& passes = {}, Progress* progress = nullptr,
    const SlabGrid* slabs = nullptr);

/// The frame's slabs before any raise: --slab voxel lengths thick, but no thinner than
/// LevelOfDetail::latticePixels / 16 (--lod; --supersample-span at --lod 0) pixel widths at the nearest active
/// voxel (docs/equations.md#slabs-that-follow-the-pixels-far-away), from the eye (perspective:
/// distance along the ray) or the near plane (orthographic: depth).
SlabGrid frameSlabs(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings);

/// How many of @a slabs a kernel of lattice spacing @a spacing (kernelSigmaVoxels) spans at
/// most along any ray of an affine grid: its kDepthTruncation sigmas either side of its centre,
/// stretched by at most the Frobenius norm of the grid's transform.
double slabsSpanned(const GridSource::Impl& grid, const SlabGrid& slabs, const RenderSettings& settings, double spacing);

/// The widest lattice spacing (voxels) whose coarse kernels span at most kSlabSpanTarget of
/// @a slabs along any ray (slabsSpanned, the streamed frame's test), so that tiles seen small
/// never raise the slab thickness (LevelOfDetail::latticeLevel); +inf for grids that are not
/// affine.
double widestLatticeSpacing(const GridSource::Impl& grid, const SlabGrid& slabs, const RenderSettings& settings);

} // namespace detail
} // namespace vdb_ewa
