/// @file scene.cpp
#include <vdb_ewa/renderer.h>
#include <vdb_ewa/scene.h>

#include "coarse_image.h"
#include "frame_lights.h"
#include "pixel_size.h"
#include "support/progress.h"

#include <mutex>

namespace vdb_ewa {

struct Scene::Impl
{
    Impl(GridSource g, const RenderSettings& s) : grid(std::move(g)), settings(s), lights(&grid.impl()), coarseLights(&grid.impl()) {}
    GridSource grid;
    RenderSettings settings;
    detail::LightCache lights;       ///< kept while their key (detail::lightKey) holds
    detail::LightCache coarseLights; ///< a progressive render's coarse images' (detail::coarseSettings)
    mutable std::mutex rendering; ///< one render at a time: the kept maps are filled as it runs

    /// A render with @a with, the kept maps @a kept handed to it (the caller holds `rendering`).
    Frame render(const RenderSettings& with, const Camera& camera, const PassRequest& passes, RenderStats* stats, Interrupter* interrupter,
        detail::LightCache& kept);
    /// The coarse image of a progressive render (detail::coarseSettings at @a scale): one
    /// sample a scale x scale block, interpolated back to the camera's pixels.
    Frame renderCoarse(const RenderSettings& with, const Camera& camera, int scale, const PassRequest& passes, RenderStats& stats,
        Interrupter* interrupter);
};

namespace {

/// The part [from, to] percent of a progressive render's progress: one rising report for its
/// renders, each of which reports 0 to 100. A cancel of the render's interrupter reaches the
/// part at its next check (Progress asks at most every 50 ms).
class PartOfProgress : public Interrupter
{
public:
    PartOfProgress(Interrupter* whole, int from, int to) : mWhole(whole), mFrom(from), mTo(to) {}
    bool wasInterrupted(int percent) override
    {
        if (!mWhole) return false;
        return mWhole->wasInterrupted(mFrom + (mTo - mFrom) * percent / 100) || mWhole->cancelled();
    }

private:
    Interrupter* mWhole;
    int mFrom, mTo;
};

/// The coarse image's share of a progressive render's progress, percent.
constexpr int kCoarseShare = 10;

} // namespace

Scene::Scene(GridSource grid, const RenderSettings& settings)
{
    settings.validate();
    mImpl = std::make_unique<Impl>(std::move(grid), settings);
}

Scene::~Scene() = default;
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;

const GridSource& Scene::grid() const { return mImpl->grid; }
RenderSettings Scene::settings() const
{
    const std::lock_guard<std::mutex> lock(mImpl->rendering);
    return mImpl->settings;
}

void Scene::setSettings(const RenderSettings& settings)
{
    settings.validate();
    const std::lock_guard<std::mutex> lock(mImpl->rendering);
    mImpl->settings = settings; // the kept maps hold their own key: the next render checks it
}

Frame Scene::render(const Camera& camera, const PassRequest& passes, RenderStats* stats, Interrupter* interrupter)
{
    const std::lock_guard<std::mutex> lock(mImpl->rendering);
    return mImpl->render(mImpl->settings, camera, passes, stats, interrupter, mImpl->lights);
}

Frame Scene::render(const Camera& camera, const RenderSettings& settings, const PassRequest& passes, RenderStats* stats,
    Interrupter* interrupter)
{
    const std::lock_guard<std::mutex> lock(mImpl->rendering);
    return mImpl->render(settings, camera, passes, stats, interrupter, mImpl->lights);
}

Frame Scene::render(const Camera& camera, const RenderSettings& settings, const ProgressiveCallback& progressive,
    const PassRequest& passes, RenderStats* stats, Interrupter* interrupter)
{
    settings.validate();
    const std::lock_guard<std::mutex> lock(mImpl->rendering);
    const detail::InterrupterBracket bracket(interrupter, mImpl->grid.name());
    const int scale = detail::coarseScale(camera);
    if (scale > 1) {
        PartOfProgress part(interrupter, 0, kCoarseShare);
        RenderStats coarseStats;
        const Frame coarse = mImpl->renderCoarse(settings, camera, scale, passes, coarseStats, interrupter ? &part : nullptr);
        if (progressive) progressive(coarse, coarseStats);
        if (interrupter && (interrupter->cancelled() || interrupter->wasInterrupted(kCoarseShare))) throw Cancelled();
    }
    PartOfProgress part(interrupter, scale > 1 ? kCoarseShare : 0, 100);
    RenderStats ownStats;
    RenderStats& out = stats ? *stats : ownStats;
    Frame frame = mImpl->render(settings, camera, passes, &out, interrupter ? &part : nullptr, mImpl->lights);
    if (progressive) progressive(frame, out);
    return frame;
}

Frame Scene::Impl::renderCoarse(const RenderSettings& with, const Camera& camera, int scale, const PassRequest& passes, RenderStats& stats,
    Interrupter* interrupter)
{
    PassRequest coarsePasses = passes;
    coarsePasses.deep = false; // deep samples have no interpolation
    detail::LightCache& kept = detail::coarseLightsAreAsked(with) ? lights : coarseLights;
    Frame big = render(detail::coarseSettings(with), camera.withPixelSize(scale), coarsePasses, &stats, interrupter, kept);
    stats.coarseScale = scale;
    return detail::upsampled(std::move(big), scale, camera.width(), camera.height(), coarsePasses);
}

Frame Scene::Impl::render(const RenderSettings& with, const Camera& camera, const PassRequest& passes, RenderStats* stats,
    Interrupter* interrupter, detail::LightCache& kept)
{
    Renderer renderer(with);
    renderer.mLightCache = &kept;
    try {
        return renderer.renderFrame(grid, camera, passes, stats, interrupter);
    } catch (...) {
        // A cancelled march may have left a tile of rays half written: nothing stale is kept.
        kept.clear();
        throw;
    }
}

void Scene::clear()
{
    const std::lock_guard<std::mutex> lock(mImpl->rendering);
    mImpl->lights.clear();
    mImpl->coarseLights.clear();
}

} // namespace vdb_ewa
