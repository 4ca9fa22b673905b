/// @file frame_parts.cpp
#include "frame_parts.h"

#include "raster/raster.h"
#include "shading/shading.h"

#include <algorithm>
#include <type_traits>
#include <sstream>
#include <tuple>
#include <utility>

namespace vdb_ewa {
namespace detail {

MemoryBudget budgetFor(const GridSource::Impl& grid, const RenderSettings& settings)
{
    return MemoryBudget(settings.maxMemory,
        (grid.path.empty() ? std::string("host grid") : grid.path) + ": grid '" + grid.name + "'");
}

std::string countLine(std::uint64_t n, const std::string& what)
{
    std::ostringstream s;
    s << n << " " << what;
    return s.str();
}

int subFrameCount(const RenderSettings& settings, bool moving, bool lens, bool deep)
{
    return deep ? 1 : std::max(moving ? settings.motionBlur.samples : 1, lens ? settings.lensSamples : 1);
}

RenderSettings subFrameSettings(const RenderSettings& settings, bool moving, int s, int n)
{
    RenderSettings part = settings;
    part.motionBlur.samples = 1;
    part.lensSamples = 1;
    if (moving) {
        const MotionBlur& blur = settings.motionBlur;
        part.motionBlur.shutterOpen = blur.shutterOpen + (blur.shutterClose - blur.shutterOpen) * double(s) / double(n);
        part.motionBlur.shutterClose = blur.shutterOpen + (blur.shutterClose - blur.shutterOpen) * double(s + 1) / double(n);
    }
    return part;
}

void addToAverage(Frame& average, Frame&& sub, int s, int n)
{
    const float w = 1.0f / float(n);
    if (s == 0) {
        average = std::move(sub);
        for (float& v : average.beauty.rgba) v *= w;
        for (std::vector<float>* plane : {&average.transmittance, &average.shadow, &average.emission})
            for (float& v : *plane) v *= w;
        return;
    }
    for (std::size_t i = 0; i < average.beauty.rgba.size(); ++i) average.beauty.rgba[i] += w * sub.beauty.rgba[i];
    for (const auto& [to, from] : {std::pair{&average.transmittance, &sub.transmittance}, {&average.shadow, &sub.shadow}, {&average.emission, &sub.emission}})
        for (std::size_t i = 0; i < to->size(); ++i) (*to)[i] += w * (*from)[i];
    for (std::size_t i = 0; i < average.depth.size(); ++i) average.depth[i] = std::min(average.depth[i], sub.depth[i]);
}

void addPartStats(RenderStats& stats, RenderStats&& part, bool first)
{
    const RenderStats total = stats;
    stats = std::move(part);
    if (first) return;
    stats.kernelSeconds += total.kernelSeconds;
    stats.shadowSeconds += total.shadowSeconds;
    stats.projectSeconds += total.projectSeconds;
    stats.rasterSeconds += total.rasterSeconds;
    for (auto [sum, add] : {std::pair{&stats.kernels, total.kernels}, {&stats.splats, total.splats}, {&stats.splatTilePairs, total.splatTilePairs},
             {&stats.splatTilePairsSkipped, total.splatTilePairsSkipped}, {&stats.footprintSamples, total.footprintSamples},
             {&stats.slabComposites, total.slabComposites}, {&stats.motionSubKernels, total.motionSubKernels},
             {&stats.bricksExpanded, total.bricksExpanded}, {&stats.bricksHidden, total.bricksHidden}, {&stats.windows, total.windows},
             {&stats.lightRaysMarched, total.lightRaysMarched}, {&stats.lightRaysReused, total.lightRaysReused},
             {&stats.lightMapsReused, total.lightMapsReused}, {&stats.kernelsCulled, total.kernelsCulled}})
        *sum += add;
    for (int k = 0; k < kImageLevels; ++k) stats.footprintSamplesAtLevel[k] += total.footprintSamplesAtLevel[k];
    for (int k = 0; k < kImageLevels; ++k) stats.slabCompositesAtLevel[k] += total.slabCompositesAtLevel[k];
}

Frame assembleChannels(Frame (&channels)[3])
{
    Frame frame = std::move(channels[0]);
    const std::size_t pixels = frame.beauty.rgba.size() / 4;
    for (std::size_t i = 0; i < pixels; ++i) {
        frame.beauty.rgba[4 * i + 1] = channels[1].beauty.rgba[4 * i + 1];
        frame.beauty.rgba[4 * i + 2] = channels[2].beauty.rgba[4 * i + 2];
        frame.beauty.rgba[4 * i + 3] = (frame.beauty.rgba[4 * i + 3] + channels[1].beauty.rgba[4 * i + 3] + channels[2].beauty.rgba[4 * i + 3]) / 3.0f;
        for (const auto& [plane, g, b] : {std::tuple{&frame.transmittance, &channels[1].transmittance, &channels[2].transmittance},
                 {&frame.shadow, &channels[1].shadow, &channels[2].shadow}, {&frame.emission, &channels[1].emission, &channels[2].emission}}) {
            if (plane->empty()) continue;
            (*plane)[3 * i + 1] = (*g)[3 * i + 1];
            (*plane)[3 * i + 2] = (*b)[3 * i + 2];
        }
        if (!frame.depth.empty()) frame.depth[i] = std::min({frame.depth[i], channels[1].depth[i], channels[2].depth[i]});
    }
    return frame;
}

void addRasterStats(const RasterStats& raster, RenderStats& stats)
{
    stats.splatTilePairs = raster.splatTilePairs;
    stats.screenTiles = raster.tiles;
    stats.screenTilesOpaque = raster.tilesOpaque;
    stats.splatTilePairsSkipped = raster.pairsSkipped;
    stats.footprintSamples = raster.footprintSamples;
    static_assert(std::extent_v<decltype(RenderStats::footprintSamplesAtLevel)> == kImageLevels, "RenderStats: one count per image level");
    for (int k = 0; k < kImageLevels; ++k) stats.footprintSamplesAtLevel[k] = raster.levelSamples[k];
    stats.slabComposites = raster.slabComposites;
    static_assert(std::extent_v<decltype(RenderStats::slabCompositesAtLevel)> == kImageLevels, "RenderStats: one count per image level");
    for (int k = 0; k < kImageLevels; ++k) stats.slabCompositesAtLevel[k] = raster.levelComposites[k];
    stats.rasterBackend = raster.backend;
}

void valueWarnings(std::uint64_t notANumber, std::uint64_t clamped, std::vector<std::string>& warnings)
{
    if (notANumber) warnings.push_back(countLine(notANumber, "NaN voxel values skipped"));
    if (clamped) warnings.push_back(countLine(clamped, "voxel values above 1e6 (or +Inf) clamped to 1e6"));
}

void addMotionStats(const MotionStats& motion, RenderStats& stats)
{
    stats.movingKernels += motion.moving;
    stats.motionSubKernels += motion.subKernels;
}

void motionWarnings(const MotionStats& motion, double splitSigmas, std::vector<std::string>& warnings)
{
    if (motion.clamped) {
        warnings.push_back(countLine(motion.clamped, "kernels travelled more than 4096 voxel lengths over the shutter and were slowed to it "
                                                     "(check --velocity-scale, --velocity-unit and --fps)"));
    }
    if (motion.longPaths) {
        std::ostringstream what;
        what << "kernels travelled so far that " << kMaxSubKernels << " sub-kernels each stand for more than " << splitSigmas
             << " of their standard deviations of the path (--motion-split; the blur is smoother than a box there)";
        warnings.push_back(countLine(motion.longPaths, what.str()));
    }
}

void splatWarnings(std::uint64_t beforeNear, std::uint64_t clampedNear, std::uint64_t clampedGrazing, std::uint64_t clippedSpan,
    std::vector<std::string>& warnings)
{
    if (beforeNear) warnings.push_back(countLine(beforeNear, "voxels in front of the near plane left out (lower --near to see them)"));
    if (clampedNear) warnings.push_back(countLine(clampedNear, "voxels around the camera drawn as if a little further away (the camera is inside the volume; move it out for an exact image)"));
    if (clampedGrazing) warnings.push_back(countLine(clampedGrazing, "voxels far outside the frame drawn with the perspective of its edge (only the image's border can show it; widen --fov to include them)"));
    if (clippedSpan) warnings.push_back(countLine(clippedSpan, "voxels crossed more than 1024 depth slabs and were cut short (raise --slab)"));
}

double lightMapPoints(const RenderSettings& settings, const MemoryBudget& budget)
{
    const OpticalModel model(settings);
    std::size_t lit = 0;
    for (std::size_t l = 0; l < settings.lights.size(); ++l) lit += model.dark(l) ? 0 : 1;
    for (std::size_t l = 0; l < settings.pointLights.size(); ++l) lit += model.pointDark(l) ? 0 : 1;
    return std::min(kLightMapPointBudget, budget.itemsWithin(0.25, 4.0)) / double(std::max<std::size_t>(lit, 1));
}

PointLights pointLightMaps(const RenderSettings& settings, const GridSource::Impl& g, const MemoryBudget& budget,
    Progress& progress, std::vector<std::string>& warnings)
{
    if (settings.pointLights.empty()) return {};
    const double points = lightMapPoints(settings, budget);
    PointLights lights(g, settings, points, &progress);
    for (const PointLightMap& map : lights.maps()) {
        if (map.shadowStep() == settings.shadow.step && map.shadowResolution() == settings.shadow.resolution) continue;
        std::ostringstream w;
        w << "--shadowstep raised from " << settings.shadow.step << " to " << map.shadowStep() << " and --shadow-res from "
          << settings.shadow.resolution << " to " << map.shadowResolution() << " voxels for a point or spot light: finer shadows would need more than their share of memory ("
          << points << " light-map points a light; raise --max-memory)";
        warnings.push_back(w.str());
        break;
    }
    return lights;
}

bool lightMapsOutgrowFrame(const RenderSettings& settings, const GridSource::Impl& g, const MemoryBudget& budget, double pixels)
{
    const double lightPoints = lightMapPoints(settings, budget);
    for (std::size_t l = 0; l < settings.lights.size(); ++l) {
        if (LightMap::plannedPoints(g, settings, l, lightPoints) > kLightPointsPerPixelMarchedWhole * pixels) return true;
    }
    return false;
}

std::vector<LightMap> lightMaps(const RenderSettings& settings, const GridSource::Impl& g, const MemoryBudget& budget,
    Progress& progress, std::vector<std::string>& warnings, bool onDemand)
{
    const double lightPoints = lightMapPoints(settings, budget);
    std::vector<LightMap> lights;
    lights.reserve(settings.lights.size());
    for (std::size_t l = 0; l < settings.lights.size(); ++l) lights.emplace_back(g, settings, l, &progress, lightPoints, onDemand);
    for (const LightMap& light : lights) {
        if (light.shadowStep() == settings.shadow.step && light.shadowResolution() == settings.shadow.resolution) continue;
        std::ostringstream w;
        w << "--shadowstep raised from " << settings.shadow.step << " to " << light.shadowStep() << " and --shadow-res from "
          << settings.shadow.resolution << " to " << light.shadowResolution()
          << " voxels: finer shadows would need more than their share of memory (" << lightPoints << " light-map points a light; raise --max-memory)";
        warnings.push_back(w.str());
        break;
    }
    return lights;
}

bool greyFrame(const RenderSettings& settings, const GridSource::Impl& g)
{
    const OpticalModel model(settings);
    const auto grey = [](double r, double gr, double b) { return float(r) == float(gr) && float(r) == float(b); };
    if (g.color || !grey(model.extinction(0), model.extinction(1), model.extinction(2))) return false;
    if (!grey(model.emitted(0), model.emitted(1), model.emitted(2)) || !grey(model.ambient(0, 1.0), model.ambient(1, 1.0), model.ambient(2, 1.0))) {
        return false;
    }
    for (std::size_t l = 0; l < settings.lights.size(); ++l) {
        if (!grey(model.lightScale(l, 0), model.lightScale(l, 1), model.lightScale(l, 2))) return false;
    }
    for (std::size_t l = 0; l < settings.pointLights.size(); ++l) {
        if (!grey(model.pointScale(l, 0), model.pointScale(l, 1), model.pointScale(l, 2))) return false;
    }
    return true;
}

} // namespace detail
} // namespace vdb_ewa
