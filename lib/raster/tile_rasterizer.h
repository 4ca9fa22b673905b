/// @file tile_rasterizer.h
/// @brief Splats -> image: bin splats to 16x16 screen tiles, then per tile sweep the
///        image-aligned slabs front to back (Sec. 7.1; Mueller & Crawfis sheet buffers).
#pragma once

#include "projection/projection.h"
#include "raster/surface_layer.h"
#include "raster/tile_bins.h"
#include "shading/shading.h"

#include <vdb_ewa/frame.h>

namespace vdb_ewa {
namespace detail {

struct RasterStats
{
    std::uint64_t splatTilePairs = 0;
    std::uint64_t tiles = 0;
    std::uint64_t tilesOpaque = 0;  ///< tiles that turned opaque before their last splat
    std::uint64_t pairsSkipped = 0; ///< pairs skipped in those tiles
    std::uint64_t footprintSamples = 0; ///< footprint weights evaluated (pixels inside a cut-off)
    std::uint64_t levelSamples[kImageLevels] = {}; ///< of them, at each image level (TileCounters::levelSamples)
    std::uint64_t slabComposites = 0;   ///< (pixel, slab) samples composited
    std::uint64_t levelComposites[kImageLevels] = {}; ///< of them, at each image level (TileCounters::levelComposites)
    const char* backend = "scalar";     ///< the slab compositor: "scalar" or the SIMD target's name
};

/// Composite @a set into the camera's image (premultiplied RGB, A = 1 - mean T) and the
/// requested passes (include/vdb_ewa/frame.h, docs/output.md). Each tile is owned by one task
/// and processes its splats in (first slab, kernel) order, so the result does not depend on
/// the thread count.
/// @a light: the light map that lights the splats' scattering weights at every (pixel, slab)
/// sample (null: unlit); @a tinted: the splats' scattering weights carry material colours.
/// @a progress: one unit per screen tile; throws Cancelled. @a budget: the splat-tile pairs are
/// counted against it before they are stored (BudgetError).
/// @a surface: a surface composited at its depth in each pixel's slab sweep (fog --iso
/// surfaces: before the first slab whose middle lies behind it), with its coverage as
/// opacity; @a surfaceShadow: the light's transmittance at it, for the shadow pass.
/// @a pointLights: the point and spot lights, lit per slab sample too (null: none).
Frame rasterizeSplats(const SplatSet& set, const Camera& camera, const RenderSettings& settings,
    const PassRequest& passes, RasterStats& stats, const std::vector<LightMap>& lights = {}, bool tinted = false,
    Progress* progress = nullptr, const MemoryBudget* budget = nullptr, const SurfaceLayer* surface = nullptr,
    const SurfaceLayer* surfaceShadow = nullptr, const PointLights* pointLights = nullptr);

} // namespace detail
} // namespace vdb_ewa
