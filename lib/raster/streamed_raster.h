/// @file streamed_raster.h
/// @brief The volume rasteriser of the streamed frame (docs/architecture.md#the-streamed-frame):
///        windows of splats composited front to back into tiles kept between windows, and which
///        screen tiles are opaque so far, the occlusion summary that culls what lies behind.
#pragma once

#include "raster/tile_rasterizer.h"

#include <memory>
#include <vector>

namespace vdb_ewa {
namespace detail {

struct FrameCompositing;
class SlabStream;
struct TileDeep;
struct TileCounters;

class StreamedRaster
{
public:
    /// A frame of @a camera's size; the splats of every window share @a slabs. @a tinted: the
    /// splats' scattering weights carry material colours; @a grey: every splat's optical depth
    /// and source terms will be the same in R, G and B (one channel carried, see
    /// scalarSlabCompositor). @a budget: each window's splat-tile pairs are counted against it.
    /// @a pointLights: the point and spot lights (null: none), which must outlive it.
    /// @a maxShift: motion blur's largest move (world units, largestTravel; 0: none): the
    /// splats carry their moves, and the light is looked up where their material came from.
    /// @a layers: motion blur's shutter layers (CompositeOptions::layers; 1 where nothing moves
    /// or deep samples are asked for).
    StreamedRaster(const Camera& camera, const RenderSettings& settings, const PassRequest& passes, const std::vector<LightMap>& lights,
        bool tinted, bool grey, const SlabGrid& slabs, const MemoryBudget* budget, const PointLights* pointLights = nullptr,
        double maxShift = 0.0, int layers = 1);
    ~StreamedRaster();
    StreamedRaster(const StreamedRaster&) = delete;
    StreamedRaster& operator=(const StreamedRaster&) = delete;

    /// Composite a window's splats, whose first slabs lie at or behind the previous window's
    /// end and before @a windowEnd, then every slab in front of @a windowEnd. Throws Cancelled.
    void composite(const SplatSet& window, std::int64_t windowEnd, Progress* progress);

    int tilesX() const { return mTilesX; }
    int tilesY() const { return mTilesY; }
    /// Every screen tile of the inclusive rectangle [tx0, tx1] x [ty0, ty1] is opaque: nothing
    /// behind what was composited can change it (a summed-area table, O(1)).
    bool hidden(int tx0, int ty0, int tx1, int ty1) const;
    /// The screen tiles opaque so far.
    std::uint32_t opaqueTiles() const { return mOpaqueSums.back(); }

    /// The frame: pixels, passes and deep image; the counters into @a stats.
    Frame finish(RasterStats& stats);

private:
    const Camera& mCamera;
    PassRequest mPasses;
    const MemoryBudget* mBudget;
    int mTilesX, mTilesY;
    std::unique_ptr<FrameCompositing> mCompositing;
    std::unique_ptr<SlabStream> mStream;
    RasterStats mStats;
    Frame mFrame;                    ///< what the tiles write as they finish
    std::vector<float> mDepthScale;  ///< camera depth per unit of ray distance (Z and deep samples only)
    std::vector<TileDeep> mDeep;
    std::vector<TileCounters> mCounters;
    std::vector<std::uint32_t> mOpaqueSums; ///< (tilesX + 1) x (tilesY + 1) summed-area table of opaque tiles
};

} // namespace detail
} // namespace vdb_ewa
