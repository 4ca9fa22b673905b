/// @file surface_projection.h
/// @brief Surface kernels -> screen-space footprints (Sec. 6.4, Eq. 35) for the surface
///        rasteriser (level sets and fog --iso surfaces).
#pragma once

#include "projection/disc_coverage.h"
#include "projection/splat_projection.h"
#include "source/source.h"
#include "support/huge_page_allocator.h"
#include "support/rgb.h"

#include <vector>

namespace vdb_ewa {
namespace detail {

/// Whether @a kernel can be drawn through @a camera: it lies between the near and far planes and
/// faces the eye (back faces are hidden by the front of the same surface). Its camera-space
/// centre @a t and @a normal.
bool facesEye(const SurfaceKernel& kernel, const Camera& camera, Vec3d& t, Vec3d& normal);

/// Whether any part of the world box [@a lo, @a hi] may be seen through @a camera: it does not lie
/// wholly outside one plane of the view frustum (near, far, and the frame's four sides pushed
/// out by @a pixelMargin pixels).
bool boxMayBeSeen(const Camera& camera, const Vec3d& lo, const Vec3d& hi, double pixelMargin);

/// The surface kernels a render of a surface (a level set, a fog --iso surface) through @a camera needs, on the lattice @a lattice
/// (voxels of @a voxelLength): only the kernels facing the eye are related to their neighbours,
/// and leaf nodes whose kernels cannot reach the frame are skipped. A kernel reaches the frame
/// through its footprint (settings.splat.cutoffRadius sigma, widened by the low-pass filter) or
/// its disc (kDiscRadiusSigmas sigma): the leaves' boxes are widened by the larger in world
/// units and the frame by the filter's reach in pixels. The image is bit-identical to that of
/// every kernel (SurfaceCoverage.RelatingOnlyTheDrawnKernelsLeavesTheImageUnchanged).
SurfaceRequest levelSetRequest(const RenderSettings& settings, const Camera& camera, double voxelLength, int lattice);

/// The footprint (Eq. 35) of a surface kernel of tangential std. deviation @a sigma with
/// camera-space centre @a t and @a normal (as facesEye gives them). False if it does not project.
bool projectSurface(const Vec3d& t, const Vec3d& normal, double sigma, const ProjectionParams& params, Footprint& fp);

/// A projected, shaded surface kernel.
struct SurfaceSplat
{
    float cx, cy;          ///< centre, raster
    float qa, qb, qc;      ///< conic, 1/pixels^2
    float cutoff;          ///< the filtered footprint: weights where d^T Q d < cutoff
    float weight;          ///< area x footprint peak
    float colour[3];       ///< shaded colour
    double depth;          ///< camera depth of the centre
    DiscCoverage disc;     ///< the kernel's disc in its tangent plane, seen from the camera
    double depthRange;     ///< plane depths along a ray are clamped to depth +- this: the disc
                           ///< and two pixels' width (the filtered footprint reaches that far)
    int x0, y0, x1, y1;
};

/// What the surface rasteriser receives (raster/surface_rasterizer.h): a surface's splats,
/// projected and shaded, and what its z-buffer needs of the kernels.
struct SurfaceSplatSet
{
    /// One per kernel facing the eye, in the kernels' order; those outside the frame have an
    /// empty pixel box (x1 < x0). Only the kernels facing the eye take memory.
    LargeArray<SurfaceSplat> splats;
    std::size_t kernels = 0; ///< the surface's kernels, facing the eye or not
    double spacing = 0.0;    ///< SurfaceSet::spacing: the unit of the depth layers' tolerance
};

/// The surface splats (Eq. 35) of @a set through @a camera: each kernel facing the eye
/// projected with the filtered footprint's cut-off at kSurfaceCutoffRadius sigma (at most
/// --cutoff-radius), its disc seen through the camera (disc_coverage.h), and shaded with
/// settings.surface.shader, or coloured @a colours[i] (index-aligned with the kernels: fog
/// --iso surfaces lit by the light) where given.
SurfaceSplatSet projectSurfaceSplats(const SurfaceSet& set, const Camera& camera, const RenderSettings& settings,
    const std::vector<Rgb>* colours = nullptr);

} // namespace detail
} // namespace vdb_ewa
