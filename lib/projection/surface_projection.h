/// @file surface_projection.h
/// @brief Surface kernels -> screen-space footprints (Sec. 6.4, Eq. 35) for the surface
///        rasteriser (level sets and fog --iso surfaces).
#pragma once

#include "projection/splat_projection.h"
#include "source/source.h"

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

} // namespace detail
} // namespace vdb_ewa
