/// @file frame_compositing.h
/// @brief What the volume rasteriser's two orders of work share (the whole frame,
///        tile_rasterizer.cpp; the streamed frame, streamed_raster.cpp): the options every tile
///        shares, the sweep order's bins, the backend, the deep image and the counters.
#pragma once

#include "raster/slab_compositor.h"
#include "raster/tile_rasterizer.h"

#include <memory>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// The compositing of one frame: the optical model, the exp table and the options that point
/// at them (so neither copied nor moved).
struct FrameCompositing
{
    /// @a emissive: some splat may carry a pre-shaded source term (Splat::emission).
    /// @a pointLights: the point and spot lights (null or empty: none), which must outlive it.
    FrameCompositing(const Camera& camera, const RenderSettings& settings, const PassRequest& passes, const std::vector<LightMap>& lights,
        bool tinted, bool emissive, const SlabGrid& slabs, const PointLights* pointLights = nullptr);
    FrameCompositing(const FrameCompositing&) = delete;
    FrameCompositing& operator=(const FrameCompositing&) = delete;

    OpticalModel model;
    ExpTable table;
    CompositeOptions options;
};

/// @a set's splats binned to the screen tiles in the sweep order (first slab, then splat
/// index): every tile's list needs no sort of its own. @a budget: the pairs are counted first.
TileBins binInSweepOrder(const SplatSet& set, int width, int height, const MemoryBudget* budget);

/// The slab compositor backend @a settings ask for (SIMD where the CPU has it), carrying
/// @a channels; names it in @a stats.backend.
std::unique_ptr<SlabCompositor> slabCompositorFor(const RenderSettings& settings, int channels, RasterStats& stats);

/// Camera depth per unit of distance along each pixel centre's ray (frame order).
std::vector<float> depthScales(const Camera& camera);

/// Tiles' deep samples (@a tilesX tiles a row) -> one DeepImage in pixel order, depths
/// converted to camera depth.
DeepImage assembleDeep(std::vector<TileDeep>& tiles, int tilesX, int width, int height, const std::vector<float>& depthScale);

/// The tiles' counters summed into @a stats (tiles, opaque tiles, skipped pairs, samples, composites).
void addCounters(const std::vector<TileCounters>& counters, RasterStats& stats);

} // namespace detail
} // namespace vdb_ewa
