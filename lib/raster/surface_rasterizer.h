/// @file surface_rasterizer.h
/// @brief Surface splats -> image: screen-space surface splats (Eq. 35, projected and shaded
///        by projection/surface_projection.h), composited per 16x16 tile with a z-buffer and a
///        depth tolerance, colour normalised by the accumulated weights (Zwicker et al. 2002,
///        Sec. 7.2).
#pragma once

#include "projection/projection.h"
#include "raster/surface_layer.h"
#include "support/memory_budget.h"
#include "support/progress.h"

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

/// The splats of @a surfaces (back-facing kernels culled by projectSurfaceSplats). Per pixel,
/// its (splat, pixel) pairs in depth order (the tangent plane's depth along the pixel's ray),
/// in up to 4 layers front to back: a layer's
/// front is the nearest pair whose disc covers one of the pixel's 4x4 subsamples not yet
/// covered (projection/disc_coverage.h), and the pairs within settings.surface.tolerance lattice
/// steps (SurfaceSplatSet::spacing) of it join it. Weight w = area x footprint; a layer's colour = sum w c / sum w over
/// its pairs on the kept side of their crease clips, spread over the subsamples it newly
/// covers; alpha = covered subsamples / 16. Deterministic (ties by kernel order). Z, where
/// alpha >= 0.5: the front layer's weighted mean depth. Passes: depth and transmittance
/// (1 - alpha); the others are volume passes (docs/equations.md#surface-coverage).
/// @a progress: one unit per screen tile; throws Cancelled. @a budget: the splat-tile pairs are
/// counted against it before they are stored (BudgetError).
Frame rasterizeSurfaces(const SurfaceSplatSet& surfaces, const Camera& camera, const RenderSettings& settings,
    const PassRequest& passes, SurfaceStats& stats, Progress* progress = nullptr,
    const MemoryBudget* budget = nullptr);

/// The same surface as a layer: premultiplied colour, coverage alpha and the front layer's
/// camera depth per pixel (the splats' colours as projectSurfaceSplats shaded them: fog --iso
/// surfaces are coloured by the light there).
SurfaceLayer rasterizeSurfaceLayer(const SurfaceSplatSet& surfaces, const Camera& camera, const RenderSettings& settings,
    SurfaceStats& stats, Progress* progress = nullptr, const MemoryBudget* budget = nullptr);

} // namespace detail
} // namespace vdb_ewa
