/// @file frame_lights.cpp
#include "frame_lights.h"

#include <tbb/task_arena.h>

#include <algorithm>

namespace vdb_ewa {
namespace detail {

LightKey lightKey(const RenderSettings& settings, const MemoryBudget& budget)
{
    // Everything LightMap, PointLightMap and PointLights read of the settings: the lattice's
    // budget, the march (step, spacing, gain, cutoff), the medium's extinction, and each
    // light's direction or position and cone, and what makes it dark or scales it.
    const OpticalModel model(settings);
    LightKey key = {lightMapPoints(settings, budget), settings.shadow.step, settings.shadow.resolution, settings.shadow.gain,
        settings.cutoff, model.extinction(0), model.extinction(1), model.extinction(2), double(settings.lights.size()),
        double(settings.pointLights.size())};
    for (std::size_t l = 0; l < settings.lights.size(); ++l) {
        const Vec3d d = settings.lights[l].unitDirection();
        key.insert(key.end(), {d.x, d.y, d.z, model.dark(l) ? 1.0 : 0.0});
    }
    for (std::size_t l = 0; l < settings.pointLights.size(); ++l) {
        const PointLight& p = settings.pointLights[l];
        key.insert(key.end(), {p.position.x, p.position.y, p.position.z, p.radius, p.spotAngle, p.spotTarget.x, p.spotTarget.y,
                                  p.spotTarget.z, p.spotBlend, model.pointScale(l, 0), model.pointScale(l, 1), model.pointScale(l, 2)});
    }
    return key;
}

bool LightCache::prepare(const RenderSettings& settings, const MemoryBudget& budget, Progress& progress, std::vector<std::string>& warnings)
{
    LightKey key = lightKey(settings, budget);
    const bool kept = !mKey.empty() && key == mKey;
    if (!kept) {
        clear();
        mMaps = detail::lightMaps(settings, *mGrid, budget, progress, mWarnings, true);
        mPoints = detail::pointLightMaps(settings, *mGrid, budget, progress, mWarnings);
        mKey = std::move(key);
    }
    for (LightMap& map : mMaps) map.beginRender(&progress);
    warnings.insert(warnings.end(), mWarnings.begin(), mWarnings.end());
    return kept;
}

void frameLights(FrameLights& lights, const RenderSettings& settings, const GridSource::Impl& g, const MemoryBudget& budget,
    Progress& progress, RenderStats& stats, bool onDemand, LightCache* cache)
{
    if (!cache || !cache->serves(g)) {
        lights.ownMaps = detail::lightMaps(settings, g, budget, progress, stats.warnings, onDemand);
        lights.ownPoints = detail::pointLightMaps(settings, g, budget, progress, stats.warnings);
        lights.maps = &lights.ownMaps;
        lights.points = &lights.ownPoints;
        return;
    }
    lights.kept = cache->prepare(settings, budget, progress, stats.warnings);
    lights.maps = &cache->maps();
    lights.points = &cache->points();
    if (lights.kept) stats.lightMapsReused += lights.maps->size() + lights.points->maps().size();
    if (!onDemand) {
        for (const LightMap& map : *lights.maps) map.marchRemaining();
    }
}

void addLightStats(const FrameLights& lights, RenderStats& stats)
{
    // A kept point light's rays were all marched by the render that made it.
    for (const PointLightMap& map : lights.points->maps()) {
        stats.lightRays += map.rays();
        (lights.kept ? stats.lightRaysReused : stats.lightRaysMarched) += map.rays();
    }
    // Light on demand is marched inside the compositing: its thread-time, shared out over the
    // threads, moves from the rasteriser's stage to the shadows'.
    double marching = 0.0;
    for (const LightMap& light : *lights.maps) {
        stats.lightRays += light.rays();
        stats.lightRaysMarched += light.raysMarched() - light.raysMarchedBefore();
        stats.lightRaysReused += light.raysMarchedBefore();
        marching += light.marchThreadSeconds();
    }
    marching = std::clamp(marching / double(tbb::this_task_arena::max_concurrency()), 0.0, stats.rasterSeconds);
    stats.shadowSeconds += marching;
    stats.rasterSeconds -= marching;
}

void LightCache::clear()
{
    mMaps.clear();
    mPoints = PointLights();
    mKey.clear();
    mWarnings.clear();
}

} // namespace detail
} // namespace vdb_ewa
