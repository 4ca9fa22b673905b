/// @file scene.cpp
#include <vdb_ewa/renderer.h>
#include <vdb_ewa/scene.h>

#include "frame_lights.h"

#include <mutex>

namespace vdb_ewa {

struct Scene::Impl
{
    Impl(GridSource g, const RenderSettings& s) : grid(std::move(g)), settings(s), lights(&grid.impl()) {}
    GridSource grid;
    RenderSettings settings;
    detail::LightCache lights; ///< kept while their key (detail::lightKey) holds
    std::mutex rendering;      ///< one render at a time: the kept maps are filled as it runs

    /// A render with @a with, the kept maps handed to it (the caller holds `rendering`).
    Frame render(const RenderSettings& with, const Camera& camera, const PassRequest& passes, RenderStats* stats, Interrupter* interrupter);
};

Scene::Scene(GridSource grid, const RenderSettings& settings)
{
    settings.validate();
    mImpl = std::make_unique<Impl>(std::move(grid), settings);
}

Scene::~Scene() = default;
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;

const GridSource& Scene::grid() const { return mImpl->grid; }
const RenderSettings& Scene::settings() const { return mImpl->settings; }

void Scene::setSettings(const RenderSettings& settings)
{
    settings.validate();
    const std::lock_guard<std::mutex> lock(mImpl->rendering);
    mImpl->settings = settings; // the kept maps hold their own key: the next render checks it
}

Frame Scene::render(const Camera& camera, const PassRequest& passes, RenderStats* stats, Interrupter* interrupter)
{
    const std::lock_guard<std::mutex> lock(mImpl->rendering);
    return mImpl->render(mImpl->settings, camera, passes, stats, interrupter);
}

Frame Scene::render(const Camera& camera, const RenderSettings& settings, const PassRequest& passes, RenderStats* stats,
    Interrupter* interrupter)
{
    const std::lock_guard<std::mutex> lock(mImpl->rendering);
    return mImpl->render(settings, camera, passes, stats, interrupter);
}

Frame Scene::Impl::render(const RenderSettings& with, const Camera& camera, const PassRequest& passes, RenderStats* stats,
    Interrupter* interrupter)
{
    Renderer renderer(with);
    renderer.mLightCache = &lights;
    try {
        return renderer.renderFrame(grid, camera, passes, stats, interrupter);
    } catch (...) {
        // A cancelled march may have left a tile of rays half written: nothing stale is kept.
        lights.clear();
        throw;
    }
}

void Scene::clear()
{
    const std::lock_guard<std::mutex> lock(mImpl->rendering);
    mImpl->lights.clear();
}

} // namespace vdb_ewa
