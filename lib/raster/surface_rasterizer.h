/// @file surface_rasterizer.h
/// @brief Surface kernels -> image: screen-space surface splats (Eq. 35), shaded per splat,
///        composited per 16x16 tile with a z-buffer and a depth tolerance, colour normalised
///        by the accumulated weights (Zwicker et al. 2002, Sec. 7.2).
#pragma once

#include "raster/tile_rasterizer.h"
#include "source/source.h"

#include <vdb_ewa/camera.h>
#include <vdb_ewa/frame.h>
#include <vdb_ewa/render_settings.h>

namespace vdb_ewa {
namespace detail {

struct SurfaceStats
{
    std::uint64_t splats = 0;
    std::uint64_t culled = 0; ///< outside the frustum, before the near plane
    std::uint64_t splatTilePairs = 0;
};

/// Back-facing kernels are culled. Per pixel, two passes over its splats: the front surface is
/// the nearest depth at which the pixel's ray meets a kernel's disc (3 sigma; at silhouettes,
/// where only filtered tails reach, the nearest tail), then every splat whose tangent-plane
/// depth along the ray is within settings.surface.tolerance voxel lengths of it is accumulated
/// in kernel order (deterministic). Weight w = area x footprint; colour = sum w c / sum w;
/// alpha = min(1, sum w / 0.9) (the kernels' areas make sum w = 1 inside a surface, to a few
/// per cent). Z, where alpha >= 0.5: the weighted mean of the splats' tangent-plane depths
/// along the pixel's ray. Passes: depth and transmittance (1 - alpha); the others are volume
/// passes.
/// @a progress: one unit per screen tile; throws Cancelled. @a budget: the splat-tile pairs are
/// counted against it before they are stored (BudgetError).
Frame rasterizeSurfaces(const SurfaceSet& surfaces, const Camera& camera, const RenderSettings& settings,
    double voxelLength, const PassRequest& passes, SurfaceStats& stats, Progress* progress = nullptr,
    const MemoryBudget* budget = nullptr);

} // namespace detail
} // namespace vdb_ewa
