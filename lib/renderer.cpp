/// @file renderer.cpp
/// @brief The pipeline: kernels -> shadow transmittance -> splats -> tiles (docs/architecture.md).
#include <vdb_ewa/renderer.h>

#include <vdb_ewa/error.h>

#include "projection/projection.h"
#include "raster/raster.h"
#include "reference/reference.h"
#include "shading/shading.h"
#include "source/source.h"
#include "support/memory_budget.h"
#include "support/progress.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>
#include <sstream>

namespace vdb_ewa {
namespace {

class StageTimer
{
public:
    double lap()
    {
        const auto now = std::chrono::steady_clock::now();
        const double s = std::chrono::duration<double>(now - mStart).count();
        mStart = now;
        return s;
    }

private:
    std::chrono::steady_clock::time_point mStart = std::chrono::steady_clock::now();
};

/// The frame's memory budget, naming the grid in its errors.
detail::MemoryBudget budgetFor(const GridSource::Impl& grid, const RenderSettings& settings)
{
    return detail::MemoryBudget(settings.maxMemory,
        (grid.path.empty() ? std::string("host grid") : grid.path) + ": grid '" + grid.name + "'");
}

std::string countLine(std::uint64_t n, const std::string& what)
{
    std::ostringstream s;
    s << n << " " << what;
    return s.str();
}

/// A fog volume's --iso surface rasterised on its own with disc coverage (the level sets'
/// method: docs/equations.md#surface-coverage), for the slab compositor to composite at its
/// depth; lit as the volume is: per light, its colour x the material colour x the cosine x its
/// transmittance from its light map at the kernel, summed. shadow: the lights' transmittances
/// summed (the shadow pass). Both times --iso-opacity.
struct IsoSurface
{
    detail::SurfaceLayer layer, shadow;
};

IsoSurface isoSurface(const RenderSettings& settings, const GridSource::Impl& grid, const Camera& camera, const PassRequest& passes,
    const std::vector<detail::LightMap>& lights, detail::Progress& progress, const detail::MemoryBudget& budget)
{
    budget.check(double(grid.activeVoxels), "active voxels (surface kernels)", detail::kBytesPerKernel);
    // Two layers of 5 floats a pixel (colour, coverage, depth) and the depth along each ray.
    budget.check(double(camera.width()) * double(camera.height()), "pixels of the --iso surface's layers", 44.0);
    const int lattice = detail::LevelOfDetail(grid, camera, settings).surfaceLattice(detail::kMaxSurfaceLattice);
    detail::SurfaceRequest request = detail::levelSetRequest(settings, camera, grid.voxelLength, lattice);
    request.isovalue = settings.surface.iso;
    request.outwardDecreasing = true; // the outside is where the density falls
    request.reach = detail::kReachForFog;
    const detail::SurfaceSet surfaces = detail::extractSurfaceKernels(grid, request, &progress);
    std::vector<detail::Rgb> lit(surfaces.kernels.size(), detail::Rgb{0.0f, 0.0f, 0.0f}), shadow = lit;
    for (std::size_t i = 0; i < lit.size(); ++i) {
        const detail::SurfaceKernel& k = surfaces.kernels[i];
        if (!(k.area > 0.0)) continue; // not drawn
        const Vec3d albedo = detail::workingColor(settings.inputToWorking, k.albedo);
        for (std::size_t l = 0; l < lights.size(); ++l) {
            const Vec3d& colour = settings.lights[l].color;
            if (colour.x == 0.0 && colour.y == 0.0 && colour.z == 0.0) continue; // black: as the volume's shadow pass
            const detail::Rgb t = lights[l].transmittance(lights[l].coordinates(k.pWorld));
            const double lambert = std::max(0.0, glm::dot(k.normal, settings.lights[l].unitDirection()));
            for (std::size_t c = 0; c < 3; ++c) {
                shadow[i][c] += t[c];
                lit[i][c] += float(settings.lights[l].color[int(c)] * albedo[int(c)] * lambert * double(t[c]));
            }
        }
    }
    detail::SurfaceStats stats;
    IsoSurface out;
    out.layer = detail::rasterizeSurfaceLayer(surfaces, camera, settings, stats, &progress, &budget, &lit);
    if (passes.shadow) out.shadow = detail::rasterizeSurfaceLayer(surfaces, camera, settings, stats, &progress, &budget, &shadow);
    const float opacity = float(std::clamp(settings.surface.isoOpacity, 0.0, 1.0));
    for (detail::SurfaceLayer* layer : {&out.layer, &out.shadow}) {
        for (float& v : layer->rgba) v *= opacity;
    }
    return out;
}

/// The volume rasteriser's counters in the frame's stats.
void addRasterStats(const detail::RasterStats& raster, RenderStats& stats)
{
    stats.splatTilePairs = raster.splatTilePairs;
    stats.screenTiles = raster.tiles;
    stats.screenTilesOpaque = raster.tilesOpaque;
    stats.splatTilePairsSkipped = raster.pairsSkipped;
    stats.footprintSamples = raster.footprintSamples;
    stats.slabComposites = raster.slabComposites;
    stats.rasterBackend = raster.backend;
}

/// The voxel values the kernels skipped or clamped, a line each.
void valueWarnings(std::uint64_t notANumber, std::uint64_t clamped, std::vector<std::string>& warnings)
{
    if (notANumber) warnings.push_back(countLine(notANumber, "NaN voxel values skipped"));
    if (clamped) warnings.push_back(countLine(clamped, "voxel values above 1e6 (or +Inf) clamped to 1e6"));
}

/// What the projection clamped or left out, a line each.
void splatWarnings(std::uint64_t beforeNear, std::uint64_t clampedNear, std::uint64_t clampedGrazing, std::uint64_t clippedSpan,
    std::vector<std::string>& warnings)
{
    if (beforeNear) warnings.push_back(countLine(beforeNear, "voxels in front of the near plane left out (lower --near to see them)"));
    if (clampedNear) warnings.push_back(countLine(clampedNear, "voxels around the camera drawn as if a little further away (the camera is inside the volume; move it out for an exact image)"));
    if (clampedGrazing) warnings.push_back(countLine(clampedGrazing, "voxels far outside the frame drawn with the perspective of its edge (only the image's border can show it; widen --fov to include them)"));
    if (clippedSpan) warnings.push_back(countLine(clippedSpan, "voxels crossed more than 1024 depth slabs and were cut short (raise --slab)"));
}

/// Each light's light map. They take at most a quarter of the budget (4 bytes a lattice point),
/// shared between the lights; a warning where that coarsened them.
/// The light maps' rays in all and marched, into @a stats.
void addLightStats(const std::vector<detail::LightMap>& lights, RenderStats& stats)
{
    for (const detail::LightMap& light : lights) {
        stats.lightRays += light.rays();
        stats.lightRaysMarched += light.raysMarched();
    }
}

/// The lights' maps: marched whole, or @a onDemand (the streamed frame marches what its windows need).
std::vector<detail::LightMap> lightMaps(const RenderSettings& settings, const GridSource::Impl& g, const detail::MemoryBudget& budget,
    detail::Progress& progress, std::vector<std::string>& warnings, bool onDemand = false)
{
    const detail::OpticalModel model(settings);
    std::size_t lit = 0;
    for (std::size_t l = 0; l < settings.lights.size(); ++l) lit += model.dark(l) ? 0 : 1;
    const double lightCount = double(std::max<std::size_t>(lit, 1));
    const double lightPoints = std::min(detail::kLightMapPointBudget, budget.itemsWithin(0.25, 4.0)) / lightCount;
    std::vector<detail::LightMap> lights;
    lights.reserve(settings.lights.size());
    for (std::size_t l = 0; l < settings.lights.size(); ++l) lights.emplace_back(g, settings, l, &progress, lightPoints, onDemand);
    for (const detail::LightMap& light : lights) {
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

/// Every splat's optical depth and source terms will be the same in R, G and B (the raster's
/// one-channel path), known from the settings before any splat exists: a grey medium and
/// lights, no material colours.
bool greyFrame(const RenderSettings& settings, const GridSource::Impl& g)
{
    const detail::OpticalModel model(settings);
    const auto grey = [](double r, double gr, double b) { return float(r) == float(gr) && float(r) == float(b); };
    if (g.color || !grey(model.extinction(0), model.extinction(1), model.extinction(2))) return false;
    if (!grey(model.emitted(0), model.emitted(1), model.emitted(2)) || !grey(model.ambient(0, 1.0), model.ambient(1, 1.0), model.ambient(2, 1.0))) {
        return false;
    }
    for (std::size_t l = 0; l < settings.lights.size(); ++l) {
        if (!grey(model.lightScale(l, 0), model.lightScale(l, 1), model.lightScale(l, 2))) return false;
    }
    return true;
}

/// Why the streamed frame cannot render @a g with @a settings yet (the whole frame does), or
/// null: docs/architecture.md#the-streamed-frame.
const char* notStreamable(const RenderSettings& settings, const GridSource::Impl& g)
{
    if (!settings.cull) return "--cull off";
    if (!g.linear) return "a grid transform that is not affine";
    if (g.emission || g.temperature) return "emission and temperature grids";
    if (settings.splat.refine > 1) return "--refine";
    if (!std::isnan(settings.surface.iso)) return "--iso";
    if (settings.splat.antiAliasing == AntiAliasing::Swan) return "--antialias swan";
    return nullptr;
}

} // namespace

Renderer::Renderer(const RenderSettings& settings) : mSettings(settings)
{
    mSettings.validate();
}

void Renderer::renderLevelSet(const GridSource::Impl& grid, const Camera& camera, const PassRequest& passes,
    Frame& frame, RenderStats& stats, detail::Progress& progress) const
{
    if (mSettings.method != Method::Splat) {
        throw ValueError("--method raymarch renders fog volumes; level sets are rendered with surface splats");
    }
    if (passes.shadow || passes.emission || passes.deep) {
        throw ValueError("level sets give the beauty, Z and transmittance (shadow, emission and deep passes are volume passes)");
    }
    if (!std::isnan(mSettings.surface.iso)) throw ValueError("--iso is for fog volumes; a level set's surface is chosen with --isovalue");
    if (grid.emission || grid.temperature) {
        throw ValueError("--emission-grid and --temperature light fog volumes; '" + grid.name + "' is a level set");
    }
    StageTimer timer;
    progress.stage(0, 60);
    // At most one surface kernel an active voxel.
    const detail::MemoryBudget budget = budgetFor(grid, mSettings);
    budget.check(double(grid.activeVoxels), "active voxels (surface kernels)", detail::kBytesPerKernel);
    // Level of detail: the kernels' lattice spacing projects to at most a quarter of --lod pixels.
    const int lattice = detail::LevelOfDetail(grid, camera, mSettings).surfaceLattice(detail::kMaxSurfaceLattice);
    const detail::SurfaceSet surfaces =
        detail::extractSurfaceKernels(grid, detail::levelSetRequest(mSettings, camera, grid.voxelLength, lattice), &progress);
    stats.kernelSeconds = timer.lap();
    progress.stage(60, 100);
    detail::SurfaceStats surfaceStats;
    frame = detail::rasterizeSurfaces(surfaces, camera, mSettings, passes, surfaceStats, &progress, &budget);
    stats.rasterSeconds = timer.lap();
    stats.activeVoxels = surfaces.activeVoxels;
    stats.kernels = surfaces.kernels.size();
    stats.surfaceLattice = surfaces.lattice;
    stats.kernelsCulled = surfaceStats.culled;
    stats.splats = surfaceStats.splats;
    stats.splatTilePairs = surfaceStats.splatTilePairs;
    if (surfaces.kernels.empty()) {
        std::ostringstream w;
        w << "no voxel lies next to the iso-surface " << mSettings.surface.isovalue << ": the image is empty";
        stats.warnings.push_back(w.str());
    }
}

void Renderer::renderFogVolume(const GridSource::Impl& g, const Camera& camera, const PassRequest& passes,
    Frame& frame, RenderStats& stats, detail::Progress& progress) const
{
    if (!notStreamable(mSettings, g)) {
        renderStreamedFogVolume(g, camera, passes, frame, stats, progress);
        if (stats.streamed) return;
    }
    // Progress: the stages' typical shares of a frame (docs/performance.md).
    StageTimer timer;
    progress.stage(0, 10);
    const detail::MemoryBudget budget = budgetFor(g, mSettings);
    const detail::LevelOfDetail lod(g, camera, mSettings);
    detail::KernelSet kernels = detail::extractKernels(g, mSettings, &lod, &progress, &budget);
    budget.check(double(kernels.kernels.size()), "kernels", detail::kBytesPerKernel);
    // Refined kernels where voxels are large on screen, quasi-interpolating weights for the rest.
    const double alpha = mSettings.splat.prefilter ? detail::quasiInterpolationAlpha(mSettings.splat.kernelSigma) : 0.0;
    openvdb::MaskGrid sampled(false);
    const double refinedWithin = std::min(detail::kRefinedKernelBudget, budget.itemsWithin(0.5, detail::kBytesPerKernel));
    const detail::Refinement refinement = detail::refineKernels(g, mSettings.splat.refine, alpha, float(mSettings.cutoff), lod, kernels, sampled,
        &progress, refinedWithin);
    stats.refinedVoxels = refinement.sampledVoxels;
    if (alpha > 0.0) stats.haloKernels = detail::quasiInterpolate(g, alpha, kernels, &sampled);
    const std::uint64_t densityKernels = kernels.kernels.size();
    // Emission grids' kernels after the density's (KernelSet::emitterBegin).
    detail::EmitterKernels emitters = detail::emitterKernels(g, mSettings, &lod, &progress, &budget, {refinement.n, &sampled, kernels.kernels.size()});
    const bool emittersLowered = emitters.refinementLowered;
    if (!emitters.kernels.kernels.empty()) {
        budget.check(double(kernels.kernels.size() + emitters.kernels.kernels.size()), "kernels with the emission grids'", detail::kBytesPerKernel);
        kernels.emitterBegin = kernels.kernels.size();
        kernels.kernels.reserve(kernels.kernels.size() + emitters.kernels.kernels.size());
        kernels.kernels.insert(kernels.kernels.end(), emitters.kernels.kernels.begin(), emitters.kernels.kernels.end());
        kernels.emitted = std::move(emitters.radiance);
    }
    stats.kernelSeconds = timer.lap();
    progress.stage(10, 35);
    const std::vector<detail::LightMap> lights = lightMaps(mSettings, g, budget, progress, stats.warnings);
    addLightStats(lights, stats);
    stats.shadowSeconds = timer.lap();
    if (emittersLowered) {
        std::ostringstream w;
        w << "--refine-emission lowered: refined emission and temperature kernels would need more than their share of memory ("
          << std::min(detail::kRefinedKernelBudget, budget.itemsWithin(0.25, detail::kBytesPerKernel)) << " kernels; raise --max-memory)";
        stats.warnings.push_back(w.str());
    }
    if (refinement.lowered) {
        std::ostringstream w;
        w << "--refine lowered from " << mSettings.splat.refine << " to " << refinement.n << ": the refined voxels would need more than their share of memory ("
          << refinedWithin << " kernels; raise --max-memory)";
        stats.warnings.push_back(w.str());
    }
    progress.stage(35, 45);
    const std::vector<detail::Rgb> colors = detail::kernelColors(g, kernels, mSettings.inputToWorking);
    detail::SplatSet splats = detail::projectSplats(g, kernels, colors, camera, mSettings, passes, &progress);
    std::optional<IsoSurface> iso;
    if (!std::isnan(mSettings.surface.iso)) iso = isoSurface(mSettings, g, camera, passes, lights, progress, budget);
    stats.projectSeconds = timer.lap();
    progress.stage(45, 100);
    detail::RasterStats raster;
    frame = detail::rasterizeSplats(splats, camera, mSettings, passes, raster, lights, !colors.empty(), &progress, &budget,
        iso ? &iso->layer : nullptr, iso && passes.shadow ? &iso->shadow : nullptr);
    stats.rasterSeconds = timer.lap();

    stats.activeVoxels = kernels.activeVoxels;
    stats.activeTiles = kernels.activeTiles;
    stats.kernels = kernels.kernels.size();
    stats.emitterKernels = kernels.kernels.size() - densityKernels;
    stats.kernelsSkipped = kernels.belowCutoff + kernels.notANumber;
    stats.voxelsMerged = kernels.mergedVoxels;
    stats.mergedKernels = kernels.mergedKernels;
    stats.kernelsCulled = splats.culled;
    stats.splats = splats.splats.size();
    addRasterStats(raster, stats);
    if (kernels.activeVoxels == 0 && kernels.activeTiles == 0 && stats.emitterKernels == 0) {
        stats.warnings.push_back("the grid has no active values: the image is empty");
    }
    if (emitters.kernels.clamped) {
        stats.warnings.push_back(countLine(emitters.kernels.clamped, "emitting voxels above 1e6 radiance per voxel length clamped to 1e6"));
    }
    if (emitters.hottestKelvin < detail::kVisibleKelvin) { // NaN without a temperature grid
        std::ostringstream w;
        w << "the temperature grid '" << g.temperature->name << "' reaches " << emitters.hottestKelvin << " K at most, too cold to glow visibly "
          << "(below " << detail::kVisibleKelvin << " K): --temperature-scale and --temperature-offset map its values to Kelvin";
        stats.warnings.push_back(w.str());
    }
    valueWarnings(kernels.notANumber, kernels.clamped, stats.warnings);
    splatWarnings(splats.beforeNear, splats.clampedNear, splats.clampedGrazing, 0, stats.warnings);
    if (splats.requestedThickness > 0.0) {
        std::ostringstream w;
        w << "--slab raised from " << splats.requestedThickness << " to " << splats.slabs.thickness
          << " world units so that no voxel crosses more than " << detail::kSlabSpanTarget << " depth slabs (a strongly sheared grid transform)";
        stats.warnings.push_back(w.str());
    }
    splatWarnings(0, 0, 0, splats.clippedSpan, stats.warnings);
}

void Renderer::renderStreamedFogVolume(const GridSource::Impl& g, const Camera& camera, const PassRequest& passes, Frame& frame,
    RenderStats& stats, detail::Progress& progress) const
{
    StageTimer timer;
    progress.stage(0, 5);
    const detail::MemoryBudget budget = budgetFor(g, mSettings);
    const detail::LevelOfDetail lod(g, camera, mSettings);
    const std::vector<detail::Brick> bricks = detail::listBricks(g);
    // The slabs every window shares: --slab thick, unless some kernel could span more than
    // kSlabSpanTarget of them (the whole frame raises the thickness from the kernels it made;
    // it renders those grids).
    const SlabGrid slabs = detail::frameSlabs(g, camera, mSettings);
    {
        int widest = mSettings.splat.lodPixels > 0.0 ? detail::LevelOfDetail::kLeafDim : 1;
        for (const detail::Brick& b : bricks) {
            if (!b.leaf) widest = std::max(widest, detail::tileLatticeSpacing(b.box.dim().x(), mSettings.splat.tileKernelSpacing));
        }
        const Mat3d& a = g.indexToWorldLinear;
        const double norm = std::sqrt(glm::dot(a[0], a[0]) + glm::dot(a[1], a[1]) + glm::dot(a[2], a[2])); // >= the largest stretch
        const double sd = norm * detail::kernelSigmaVoxels(detail::Kernel{Vec3d(0.0), 0.0f, float(widest)}, mSettings.splat.kernelSigma);
        if (2.0 * detail::kDepthTruncation * sd / double(detail::kSlabSpanTarget) > slabs.thickness) return;
    }
    stats.streamed = true;
    stats.bricks = bricks.size();
    stats.activeVoxels = g.activeVoxels;
    stats.activeTiles = g.activeTiles;

    // Every brick's screen rectangle and first slab, before any kernel exists.
    const detail::BrickBounder bounder(g, camera, mSettings, &lod, slabs);
    std::vector<detail::BrickBounds> bounds(bricks.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, bricks.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) bounds[i] = bounder.bound(bricks[i]);
    });
    // Front to back: by first slab, ties in tree order.
    std::vector<std::uint32_t> order;
    double voxels = 0.0;
    for (std::uint32_t i = 0; i < bricks.size(); ++i) {
        if (!bounds[i].visible) continue;
        order.push_back(i);
        voxels += bricks[i].leaf ? double(bricks[i].leaf->onVoxelCount()) : double(bricks[i].box.volume());
    }
    stats.bricksOutside = bricks.size() - order.size();
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return bounds[a].nearestSlab < bounds[b].nearestSlab; });
    stats.kernelSeconds += timer.lap();

    // Light on demand: no ray is marched yet; each window marches the rays its splats look up.
    std::vector<detail::LightMap> lights = lightMaps(mSettings, g, budget, progress, stats.warnings, true);
    stats.shadowSeconds = timer.lap();

    progress.stage(5, 100);
    progress.setUnits(order.size());
    progress.advance(0); // the windows' start is reported (the first window may take a while)
    detail::StreamedRaster raster(camera, mSettings, passes, lights, g.color != nullptr, greyFrame(mSettings, g), slabs, &budget);
    stats.rasterSeconds += timer.lap();
    const double alpha = mSettings.splat.prefilter ? detail::quasiInterpolationAlpha(mSettings.splat.kernelSigma) : 0.0;
    const detail::UnitKernelRule units{mSettings, &lod};
    // Windows grow front to back: the first holds about 1/kFirstWindow of the visible voxels,
    // each next one kGrowth times more (fine windows where the front turns opaque, few in all:
    // each costs a pass over the open tiles), none more than kWindowBytes of kernels in flight
    // or the memory budget's share. On the 10M-voxel cloud at 1080p, windows of 256, 128 and
    // 64 MiB peaked at 482, 408 and 387 MB, and 128 was the fastest
    // (docs/performance.md#memory-bounded-by-the-window).
    constexpr double kFirstWindow = 256.0, kGrowth = 2.0, kSmallestWindow = 16384.0, kWindowBytes = 128.0 * 1024.0 * 1024.0;
    const double mostVoxels = std::max(std::min(budget.itemsWithin(0.25, detail::kBytesPerKernel), kWindowBytes / detail::kBytesPerKernel), 4096.0);
    double windowVoxels = std::min(std::max(voxels / kFirstWindow, kSmallestWindow), mostVoxels), done = 0.0;
    constexpr double kFewOpaque = 0.05;
    const double tiles = double(raster.tilesX()) * double(raster.tilesY());
    constexpr double kCrossingShare = 0.5, kLargeSplatTiles = 64.0;
    constexpr int kMaxDeferred = 2;
    int deferred = 0;
    detail::SplatSet carried;
    std::uint64_t outOfOrder = 0, beforeNear = 0, clampedNear = 0, clampedGrazing = 0, clippedSpan = 0, notANumber = 0, clamped = 0;
    std::int64_t windowStart = std::numeric_limits<std::int64_t>::min();
    for (std::size_t begin = 0; begin < order.size();) {
        // The window: bricks up to about windowVoxels, ending between two first slabs.
        std::size_t end = begin;
        double held = 0.0;
        while (end < order.size() && (held < windowVoxels || bounds[order[end]].nearestSlab == bounds[order[end - 1]].nearestSlab)) {
            const detail::Brick& b = bricks[order[end++]];
            held += b.leaf ? double(b.leaf->onVoxelCount()) : double(b.box.volume());
        }
        const std::int64_t windowEnd = end < order.size() ? bounds[order[end]].nearestSlab : std::numeric_limits<std::int64_t>::max();
        ++stats.windows;
        // Bricks whose every tile is opaque already are never expanded (the occlusion summary).
        std::vector<const detail::Brick*> expanded;
        for (std::size_t k = begin; k < end; ++k) {
            const detail::BrickBounds& b = bounds[order[k]];
            if (raster.hidden(b.x0 / detail::kTileSize, b.y0 / detail::kTileSize, b.x1 / detail::kTileSize, b.y1 / detail::kTileSize)) {
                ++stats.bricksHidden;
                continue;
            }
            expanded.push_back(&bricks[order[k]]);
        }
        stats.bricksExpanded += expanded.size();
        // The window's splats: its bricks', then those earlier windows made for it (carried).
        detail::SplatSet window;
        if (!expanded.empty()) {
            detail::KernelSet kernels = detail::extractKernels(g, mSettings, &lod, nullptr, &budget, nullptr, &expanded);
            if (alpha > 0.0) stats.haloKernels += detail::quasiInterpolate(g, alpha, kernels, nullptr, &units);
            stats.kernels += kernels.kernels.size();
            stats.kernelsSkipped += kernels.belowCutoff + kernels.notANumber;
            notANumber += kernels.notANumber;
            clamped += kernels.clamped;
            stats.voxelsMerged += kernels.mergedVoxels;
            stats.mergedKernels += kernels.mergedKernels;
            const std::vector<detail::Rgb> colors = detail::kernelColors(g, kernels, mSettings.inputToWorking);
            stats.kernelSeconds += timer.lap();
            window = detail::projectSplats(g, kernels, colors, camera, mSettings, passes, nullptr, &slabs);
            stats.kernelsCulled += window.culled;
            stats.splats += window.splats.size();
            beforeNear += window.beforeNear;
            clampedNear += window.clampedNear;
            clampedGrazing += window.clampedGrazing;
            clippedSpan += window.clippedSpan;
            for (const detail::Splat& sp : window.splats) outOfOrder += sp.firstSlab < windowStart;
        }
        detail::appendSplats(window, carried);
        stats.splatsInFlight = std::max<std::uint64_t>(stats.splatsInFlight, window.splats.size());
        stats.projectSeconds += timer.lap();
        // Ending a window here leaves the slabs of the splats crossing its end pending in every
        // tile they cover, copied aside until the next window. Where a few large splats (near
        // the eye) cross it over most of the image, the window goes on into the next, up to
        // kMaxDeferred times (culling needs windows to end): pig's first windows, 200 MB of
        // pending slabs at 1080p, 0.5 s in page faults (docs/performance.md).
        double crossing = 0.0, crossingSplats = 0.0;
        for (const detail::Splat& sp : window.splats) {
            if (sp.firstSlab + std::int64_t(sp.slabCount) <= windowEnd) continue;
            crossing += double(sp.x1 / detail::kTileSize - sp.x0 / detail::kTileSize + 1) * double(sp.y1 / detail::kTileSize - sp.y0 / detail::kTileSize + 1);
            crossingSplats += 1.0;
        }
        if (crossing > kCrossingShare * tiles && crossing > kLargeSplatTiles * crossingSplats && deferred < kMaxDeferred && end < order.size()) {
            ++deferred;
            carried = std::move(window);
        } else {
            deferred = 0;
            carried = detail::splitSplatsAt(window, windowEnd);
            stats.rasterSeconds += timer.lap();
            detail::lightWindow(window, camera, lights, &progress);
            stats.shadowSeconds += timer.lap();
            raster.composite(window, windowEnd, &progress);
            windowStart = windowEnd;
        }
        stats.rasterSeconds += timer.lap();
        progress.advance(end - begin);
        begin = end;
        windowVoxels = std::min(windowVoxels * kGrowth, mostVoxels);
        // Where three windows and an eighth of the voxels left fewer than kFewOpaque of the tiles
        // opaque, little will be hidden: the rest in as few windows as the budget allows. (A
        // window composites only in front of the next one's first slab, a brick's reach in front
        // of its voxels: the first window may composite nothing yet.)
        done += held;
        if (stats.windows >= 3 && done >= voxels / 8.0 && double(raster.opaqueTiles()) < kFewOpaque * tiles) {
            windowVoxels = mostVoxels;
        }
    }
    detail::RasterStats rasterStats;
    frame = raster.finish(rasterStats);
    stats.rasterSeconds += timer.lap();
    addRasterStats(rasterStats, stats);
    addLightStats(lights, stats);
    if (outOfOrder) stats.warnings.push_back(countLine(outOfOrder, "splats started in front of their window (a bound of the streamed frame is wrong; --cull off renders without it)"));
    if (g.activeVoxels == 0 && g.activeTiles == 0) stats.warnings.push_back("the grid has no active values: the image is empty");
    // Counted in the bricks expanded: a hidden brick's values are never read.
    valueWarnings(notANumber, clamped, stats.warnings);
    splatWarnings(beforeNear, clampedNear, clampedGrazing, clippedSpan, stats.warnings);
}

std::uint64_t peakResidentBytes()
{
    std::FILE* status = std::fopen("/proc/self/status", "r");
    if (!status) return 0;
    char line[256];
    std::uint64_t kB = 0;
    while (std::fgets(line, sizeof line, status)) {
        if (std::strncmp(line, "VmHWM:", 6) == 0) {
            kB = std::strtoull(line + 6, nullptr, 10);
            break;
        }
    }
    std::fclose(status);
    return kB * 1024u;
}

Image Renderer::render(const GridSource& grid, const Camera& camera, RenderStats* statsOut, Interrupter* interrupter) const
{
    return renderFrame(grid, camera, PassRequest{}, statsOut, interrupter).beauty;
}

Frame Renderer::renderFrame(const GridSource& grid, const Camera& camera, const PassRequest& passes,
    RenderStats* statsOut, Interrupter* interrupter) const
{
    // The interrupter's start() and end() bracket the render, also when it throws.
    struct Bracket
    {
        Interrupter* interrupter;
        Bracket(Interrupter* i, const std::string& name) : interrupter(i)
        {
            if (interrupter) interrupter->start(name.c_str());
        }
        ~Bracket()
        {
            if (interrupter) interrupter->end();
        }
    } bracket(interrupter, grid.name());
    detail::Progress progress(interrupter);
    RenderStats stats;
    Frame frame;
    const GridSource::Impl& g = grid.impl();
    budgetFor(g, mSettings).check(double(camera.width()) * double(camera.height()), "pixels", detail::kBytesPerPixel);
    auto run = [&] {
        if (grid.isLevelSet()) {
            renderLevelSet(g, camera, passes, frame, stats, progress);
        } else if (mSettings.method == Method::RayMarch) {
            frame = detail::rayMarchReference(g, camera, mSettings, passes, stats, &progress);
        } else if (mSettings.method == Method::RayMarchGaussian) {
            frame = detail::rayMarchGaussianSum(g, camera, mSettings, passes, stats, &progress);
        } else {
            renderFogVolume(g, camera, passes, frame, stats, progress);
        }
    };
    if (mSettings.threads > 0) {
        tbb::task_arena arena(mSettings.threads);
        arena.execute(run);
    } else {
        run();
    }
    progress.finish();
    if (mSettings.splat.refine > 1 && (grid.isLevelSet() || mSettings.method != Method::Splat)) {
        stats.warnings.push_back(std::string("--refine changes nothing here: it refines the splatter's fog-volume kernels, not ") +
                                 (grid.isLevelSet() ? "a level set's surface kernels" : "the field --method raymarch integrates"));
    }
    // Options of the level-set path change nothing on a fog volume (an --iso surface inside
    // one is lit like the volume): say so rather than ignore them.
    const SurfaceOptions surfaceDefaults;
    if (!grid.isLevelSet() && mSettings.surface.shader != surfaceDefaults.shader) {
        stats.warnings.push_back("--shader changes nothing here: it shades level sets; a fog volume and its --iso surface are lit by --light");
    }
    if (!grid.isLevelSet() && mSettings.surface.isovalue != surfaceDefaults.isovalue) {
        stats.warnings.push_back("--isovalue changes nothing here: it picks a level set's surface; a fog volume's surface is --iso");
    }
    stats.peakResidentBytes = peakResidentBytes();
    if (statsOut) *statsOut = std::move(stats);
    return frame;
}

} // namespace vdb_ewa
