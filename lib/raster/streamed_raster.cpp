/// @file streamed_raster.cpp
#include "raster/streamed_raster.h"

#include "raster/frame_compositing.h"
#include "support/blank_frame.h"

namespace vdb_ewa {
namespace detail {

StreamedRaster::StreamedRaster(const Camera& camera, const RenderSettings& settings, const PassRequest& passes,
    const std::vector<LightMap>& lights, bool tinted, bool grey, const SlabGrid& slabs, const MemoryBudget* budget, const PointLights* pointLights,
    double maxShift, int layers)
    : mCamera(camera), mPasses(passes), mBudget(budget), mTilesX((camera.width() + kTileSize - 1) / kTileSize),
      mTilesY((camera.height() + kTileSize - 1) / kTileSize),
      // Emissive unless nothing in the model emits: the splats are not known yet.
      mCompositing(std::make_unique<FrameCompositing>(camera, settings, passes, lights, tinted, true, slabs, pointLights)),
      mOpaqueSums(std::size_t(mTilesX + 1) * std::size_t(mTilesY + 1), 0)
{
    const OpticalModel& model = mCompositing->model;
    bool emits = false;
    for (int c = 0; c < 3; ++c) emits = emits || model.emitted(c) != 0.0 || model.ambient(c, 1.0) != 0.0;
    mCompositing->options.emissive = emits;
    mCompositing->options.shifted = maxShift > 0.0;
    mCompositing->options.maxShift = maxShift;
    mCompositing->options.layers = passes.deep ? 1 : layers;
    const std::unique_ptr<SlabCompositor> backend = slabCompositorFor(settings, grey ? 1 : 3, mStats);
    mFrame = blankFrame(camera.width(), camera.height(), passes);
    if (passes.depth || passes.deep) mDepthScale = depthScales(camera);
    const std::size_t tiles = std::size_t(mTilesX) * std::size_t(mTilesY);
    mDeep.resize(passes.deep ? tiles : 0);
    mCounters.resize(tiles);
    mStream = backend->stream(mCompositing->options, StreamOutput{&mFrame, &mDepthScale, &mDeep, &mCounters});
}

StreamedRaster::~StreamedRaster() = default;

void StreamedRaster::composite(const SplatSet& window, std::int64_t windowEnd, Progress* progress)
{
    const TileBins bins = binInSweepOrder(window, mCamera.width(), mCamera.height(), mBudget);
    mStats.splatTilePairs += bins.indices.size();
    mStream->composite(window, bins, windowEnd, progress);
    for (int ty = 0; ty < mTilesY; ++ty) {
        std::uint32_t row = 0;
        for (int tx = 0; tx < mTilesX; ++tx) {
            row += mStream->opaque(ty * mTilesX + tx) ? 1u : 0u;
            mOpaqueSums[std::size_t(ty + 1) * std::size_t(mTilesX + 1) + std::size_t(tx + 1)] =
                mOpaqueSums[std::size_t(ty) * std::size_t(mTilesX + 1) + std::size_t(tx + 1)] + row;
        }
    }
}

bool StreamedRaster::hidden(int tx0, int ty0, int tx1, int ty1) const
{
    const auto at = [&](int x, int y) { return std::int64_t(mOpaqueSums[std::size_t(y) * std::size_t(mTilesX + 1) + std::size_t(x)]); };
    const std::int64_t opaque = at(tx1 + 1, ty1 + 1) - at(tx0, ty1 + 1) - at(tx1 + 1, ty0) + at(tx0, ty0);
    return opaque == std::int64_t(tx1 - tx0 + 1) * std::int64_t(ty1 - ty0 + 1);
}

Frame StreamedRaster::finish(RasterStats& stats)
{
    mStream->finish();
    mStream.reset();
    if (mPasses.deep) mFrame.deep = assembleDeep(mDeep, mTilesX, mCamera.width(), mCamera.height(), mDepthScale);
    addCounters(mCounters, mStats);
    stats = mStats;
    return std::move(mFrame);
}

} // namespace detail
} // namespace vdb_ewa
