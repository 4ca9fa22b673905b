/// @file renderer.cpp
/// @brief The pipeline: kernels -> shadow transmittance -> splats -> tiles (docs/architecture.md).
#include <vdb_ewa/renderer.h>

#include <vdb_ewa/error.h>

#include "frame_lights.h"
#include "frame_parts.h"
#include "pixel_size.h"
#include "projection/projection.h"
#include "raster/raster.h"
#include "reference/reference.h"
#include "shading/shading.h"
#include "source/source.h"
#include "support/memory_budget.h"
#include "support/progress.h"
#include "supersampling.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <sstream>

namespace vdb_ewa {

using detail::addLightStats;
using detail::addRasterStats;
using detail::budgetFor;
using detail::countLine;
using detail::splatWarnings;
using detail::StageTimer;
using detail::valueWarnings;

namespace {

/// A fog volume's --iso surface rasterised on its own with disc coverage (the level sets'
/// method: docs/equations.md#surface-coverage), for the slab compositor to composite at its
/// depth; lit as the volume is: per light, its colour x the material colour x the cosine x its
/// transmittance from its light map at the kernel, summed (point and spot lights: the cosine
/// towards the light, its falloff and its map's transmittance). shadow: the lights' transmittances
/// summed (the shadow pass). Both times --iso-opacity.
struct IsoSurface
{
    detail::SurfaceLayer layer, shadow;
};

IsoSurface isoSurface(const RenderSettings& settings, const GridSource::Impl& grid, const Camera& camera, const PassRequest& passes,
    const std::vector<detail::LightMap>& lights, const detail::PointLights& pointLights, detail::Progress& progress,
    const detail::MemoryBudget& budget)
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
        for (std::size_t l = 0; l < pointLights.lights().size(); ++l) {
            const PointLight& light = pointLights.lights()[l];
            const Vec3d toLight = light.position - k.pWorld;
            const double r = glm::length(toLight);
            const double lambert = r > 0.0 ? std::max(0.0, glm::dot(k.normal, toLight / r)) : 1.0;
            const double falloff = detail::pointLightFalloff(light, k.pWorld, grid.voxelLength);
            const std::array<double, 3> t = pointLights.transmittance(l, k.pWorld);
            for (std::size_t c = 0; c < 3; ++c) {
                shadow[i][c] += float(t[c]);
                lit[i][c] += float(light.color[int(c)] * albedo[int(c)] * lambert * falloff * t[c]);
            }
        }
    }
    detail::SurfaceStats stats;
    IsoSurface out;
    out.layer = detail::rasterizeSurfaceLayer(detail::projectSurfaceSplats(surfaces, camera, settings, &lit), camera, settings, stats, &progress, &budget);
    if (passes.shadow) {
        out.shadow = detail::rasterizeSurfaceLayer(detail::projectSurfaceSplats(surfaces, camera, settings, &shadow), camera, settings, stats, &progress, &budget);
    }
    const float opacity = float(std::clamp(settings.surface.isoOpacity, 0.0, 1.0));
    for (detail::SurfaceLayer* layer : {&out.layer, &out.shadow}) {
        for (float& v : layer->rgba) v *= opacity;
    }
    return out;
}

/// The voxels' pixels for --pixel-size: the median of those in view (a node reaching the near
/// plane is as large as its centre's depth makes it, not infinitely large as for the level of
/// detail); @a s's where --pixel-size is off (nothing more is measured).
double pixelSizeVoxelPixels(const GridSource::Impl& g, const Camera& camera, const RenderSettings& settings, const detail::Supersampling& s)
{
    if (settings.splat.pixelSize <= 1) return s.voxelPixels;
    return detail::voxelPixelsInView(g, camera, 0.5);
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
        throw ValueError("--method " + std::string(mSettings.method == Method::PathTrace ? "pathtrace" : "raymarch") + " renders fog volumes; level sets are rendered with surface splats");
    }
    if (passes.shadow || passes.emission || passes.deep) {
        throw ValueError("level sets give the beauty, Z and transmittance (shadow, emission and deep passes are volume passes)");
    }
    if (!std::isnan(mSettings.surface.iso)) throw ValueError("--iso is for fog volumes; a level set's surface is chosen with --isovalue");
    if (grid.emission || grid.temperature) {
        throw ValueError("--emission-grid and --temperature light fog volumes; '" + grid.name + "' is a level set");
    }
    if (grid.velocity) {
        stats.warnings.push_back("--velocity-grid changes nothing here: motion blur moves a fog volume's kernels; the level set renders at the frame's time");
    }
    if (camera.lensRadius() > 0.0) {
        stats.warnings.push_back("--fstop changes nothing here: depth of field blurs a fog volume's kernels; the level set renders in focus");
    }
    if (!mSettings.pointLights.empty()) {
        stats.warnings.push_back("--point-light and --spot-light change nothing here: they light fog volumes and --iso surfaces; a level set is lit by its --shader");
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
    const detail::SurfaceSplatSet splats = detail::projectSurfaceSplats(surfaces, camera, mSettings);
    stats.projectSeconds = timer.lap();
    detail::SurfaceStats surfaceStats;
    frame = detail::rasterizeSurfaces(splats, camera, mSettings, passes, surfaceStats, &progress, &budget);
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

bool Renderer::movesOverTheShutter(const GridSource::Impl& g) const
{
    return g.velocity && mSettings.motionBlur.shutterClose > mSettings.motionBlur.shutterOpen;
}

void Renderer::renderSubFrames(const GridSource::Impl& g, const Camera& camera, const PassRequest& passes,
    Frame& frame, RenderStats& stats, detail::Progress& progress) const
{
    const MotionBlur& blur = mSettings.motionBlur;
    const bool moving = movesOverTheShutter(g), lens = camera.lensRadius() > 0.0;
    if (passes.deep && moving && blur.samples > 1) {
        throw ValueError("--motion-samples averages sub-frames; a deep image has no average: use --motion-samples 1 with --deep");
    }
    const bool deepLens = passes.deep && lens && mSettings.lensSamples > 1;
    const char* const deepLensWarning = "--deep: one frame through the whole lens (--lens-samples averages sub-frames, which a deep image cannot)";
    // One sweep for every sub-frame where the streamed frame can take them (their images fit).
    if (!notStreamable(mSettings, g)) {
        renderStreamedFogVolume(g, camera, passes, frame, stats, progress);
        if (stats.streamed) {
            if (deepLens) stats.warnings.push_back(deepLensWarning);
            return;
        }
    }
    const int n = detail::subFrameCount(mSettings, moving, lens, passes.deep);
    for (int s = 0; s < n; ++s) {
        // Sub-frame s: the shutter's part s of n, seen through the lens's part s of n.
        const RenderSettings part = detail::subFrameSettings(mSettings, moving, s, n);
        Frame sub;
        RenderStats subStats;
        Renderer partRenderer(part);
        partRenderer.mLightCache = mLightCache; // the light knows no shutter: a Scene's maps serve every part
        partRenderer.renderFogVolume(g, lens ? camera.throughLensPart(s, n) : camera, passes, sub, subStats, progress);
        detail::addToAverage(frame, std::move(sub), s, n);
        // Counts and times add up over the sub-frames; the warnings are each sub-frame's alike.
        detail::addPartStats(stats, std::move(subStats), s == 0);
    }
    if (deepLens) stats.warnings.push_back(deepLensWarning);
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
    // Tiles seen small coarsen within the frame's slabs (projectSplats forms them again).
    const detail::LevelOfDetail lod(g, camera, mSettings, detail::widestLatticeSpacing(g, detail::frameSlabs(g, camera, mSettings), mSettings));
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
    // A map far larger than the frame is marched where the compositor looks it up, as the
    // streamed frame's (a file of tiles seen from afar at `final`); --cull off and an --iso
    // surface, which looks the maps up at its kernels, march them whole.
    const bool lightOnDemand = mSettings.cull && std::isnan(mSettings.surface.iso) &&
        detail::lightMapsOutgrowFrame(mSettings, g, budget, double(camera.width()) * double(camera.height()));
    detail::FrameLights frameLights;
    detail::frameLights(frameLights, mSettings, g, budget, progress, stats, lightOnDemand, mLightCache);
    const std::vector<detail::LightMap>& lights = *frameLights.maps;
    const detail::PointLights& pointLights = *frameLights.points;
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
    std::vector<detail::Rgb> colors = detail::kernelColors(g, kernels, mSettings.inputToWorking);
    const detail::MotionStats motion = detail::moveKernels(g, mSettings, camera, kernels, colors, &budget);
    detail::SplatSet splats = detail::projectSplats(g, kernels, colors, camera, mSettings, passes, &progress);
    std::optional<IsoSurface> iso;
    if (!std::isnan(mSettings.surface.iso)) iso = isoSurface(mSettings, g, camera, passes, lights, pointLights, progress, budget);
    stats.projectSeconds = timer.lap();
    progress.stage(45, 100);
    detail::RasterStats raster;
    frame = detail::rasterizeSplats(splats, camera, mSettings, passes, raster, lights, !colors.empty(), &progress, &budget,
        iso ? &iso->layer : nullptr, iso && passes.shadow ? &iso->shadow : nullptr, &pointLights);
    stats.rasterSeconds = timer.lap();
    addLightStats(frameLights, stats);

    stats.activeVoxels = kernels.activeVoxels;
    stats.activeTiles = kernels.activeTiles;
    stats.kernels = kernels.kernels.size();
    stats.emitterKernels = kernels.emitterBegin < kernels.kernels.size() ? kernels.kernels.size() - kernels.emitterBegin : 0;
    stats.kernelsSkipped = kernels.belowCutoff + kernels.notANumber;
    stats.voxelsMerged = kernels.mergedVoxels;
    stats.mergedKernels = kernels.mergedKernels;
    detail::addMotionStats(motion, stats);
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
    detail::motionWarnings(motion, mSettings.motionBlur.splitSigmas, stats.warnings);
    splatWarnings(splats.beforeNear, splats.clampedNear, splats.clampedGrazing, 0, stats.warnings);
    if (splats.requestedThickness > 0.0) {
        std::ostringstream w;
        w << "--slab raised from " << splats.requestedThickness << " to " << splats.slabs.thickness
          << " world units so that no voxel crosses more than " << detail::kSlabSpanTarget << " depth slabs (a strongly sheared grid transform)";
        stats.warnings.push_back(w.str());
    }
    splatWarnings(0, 0, 0, splats.clippedSpan, stats.warnings);
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

void Renderer::renderGrid(const GridSource::Impl& g, const Camera& camera, const PassRequest& passes, Frame& frame, RenderStats& stats,
    detail::Progress& progress) const
{
    if (g.grid->getGridClass() == openvdb::GRID_LEVEL_SET) {
        renderLevelSet(g, camera, passes, frame, stats, progress);
    } else if (mSettings.method == Method::RayMarch) {
        frame = detail::rayMarchReference(g, camera, mSettings, passes, budgetFor(g, mSettings), stats, &progress);
    } else if (mSettings.method == Method::PathTrace) {
        frame = detail::pathTrace(g, camera, mSettings, passes, stats, &progress);
    } else if (mSettings.method == Method::RayMarchGaussian) {
        frame = detail::rayMarchGaussianSum(g, camera, mSettings, passes, stats, &progress);
    } else {
        // Where the voxels look small, the pixels they cover are composited in sub-pixels and
        // box-filtered back (docs/equations.md#sub-pixel-samples).
        std::vector<std::string> warnings;
        detail::Supersampling s = detail::chooseSupersampling(g, camera, mSettings, passes, budgetFor(g, mSettings), warnings);
        // Near a change of the sampling, the other sampling's frame is mixed in with @a weight
        // (rendered by @a renderOther): no jump as the camera moves.
        const auto fadeIn = [&](double weight, const auto& renderOther) {
            if (!(weight > 0.0)) return;
            Frame other;
            RenderStats otherStats;
            renderOther(other, otherStats);
            detail::mixFrames(frame, other, weight);
            detail::addPartStats(stats, std::move(otherStats), false);
        };
        if (s.factor > 1) {
            Frame sub;
            renderSplatted(g, camera.window(s.x0, s.y0, s.width, s.height, s.factor), passes, sub, stats, progress);
            frame = detail::boxFiltered(sub, s, camera.width(), camera.height(), passes);
            // Near the span, 2 x 2 sub-pixels fade into one sample a pixel.
            fadeIn(s.blend, [&](Frame& one, RenderStats& oneStats) { renderSplatted(g, camera, passes, one, oneStats, progress); });
            stats.supersampleWindow[0] = s.x0;
            stats.supersampleWindow[1] = s.y0;
            stats.supersampleWindow[2] = s.width;
            stats.supersampleWindow[3] = s.height;
        } else {
            // Voxels seen large: one sample a size x size block of pixels, interpolated back
            // (docs/equations.md#larger-pixels); near the next size, its frame fades in.
            s.voxelPixels = pixelSizeVoxelPixels(g, camera, mSettings, s);
            const detail::PixelSize p = detail::choosePixelSize(mSettings, s.voxelPixels, passes);
            renderAtPixelSize(g, camera, p.size, passes, frame, stats, progress);
            fadeIn(p.blend, [&](Frame& next, RenderStats& nextStats) { renderAtPixelSize(g, camera, p.size + 1, passes, next, nextStats, progress); });
            stats.pixelSize = p.size;
        }
        stats.supersample = s.factor;
        stats.voxelPixels = s.voxelPixels;
        stats.warnings.insert(stats.warnings.end(), warnings.begin(), warnings.end());
    }
}

void Renderer::renderAtPixelSize(const GridSource::Impl& g, const Camera& camera, int size, const PassRequest& passes, Frame& frame,
    RenderStats& stats, detail::Progress& progress) const
{
    if (size <= 1) {
        renderSplatted(g, camera, passes, frame, stats, progress);
        return;
    }
    Frame big;
    renderSplatted(g, camera.withPixelSize(size), passes, big, stats, progress);
    frame = detail::upsampled(std::move(big), size, camera.width(), camera.height(), passes);
}

void Renderer::renderSplatted(const GridSource::Impl& g, const Camera& camera, const PassRequest& passes, Frame& frame, RenderStats& stats,
    detail::Progress& progress) const
{
    if ((movesOverTheShutter(g) && mSettings.motionBlur.samples > 1) || (camera.lensRadius() > 0.0 && mSettings.lensSamples > 1)) {
        renderSubFrames(g, camera, passes, frame, stats, progress);
    } else {
        renderFogVolume(g, camera, passes, frame, stats, progress);
    }
}

Image Renderer::render(const GridSource& grid, const Camera& camera, RenderStats* statsOut, Interrupter* interrupter) const
{
    return renderFrame(grid, camera, PassRequest{}, statsOut, interrupter).beauty;
}

Frame Renderer::renderFrame(const GridSource& grid, const Camera& camera, const PassRequest& passes,
    RenderStats* statsOut, Interrupter* interrupter) const
{
    const detail::InterrupterBracket bracket(interrupter, grid.name());
    detail::Progress progress(interrupter);
    RenderStats stats;
    Frame frame;
    const GridSource::Impl& g = grid.impl();
    budgetFor(g, mSettings).check(double(camera.width()) * double(camera.height()), "pixels", detail::kBytesPerPixel);
    auto run = [&] {
        if (g.addedMaterials.empty()) {
            renderGrid(g, camera, passes, frame, stats, progress);
            return;
        }
        // Volumes with optical models of their own: mixed into one for this render's medium.
        if (detail::extinctionsInProportion(g, mSettings) || passes.deep) { // a deep image has no channels to assemble: grey (warned)
            const detail::MixedFrame mixed = detail::mixMaterials(g, mSettings);
            Renderer(mixed.settings).renderGrid(*mixed.grid, camera, passes, frame, stats, progress);
            stats.warnings.insert(stats.warnings.begin(), mixed.warnings.begin(), mixed.warnings.end());
        } else {
            // Extinctions of different hues: once per channel, every medium grey at its
            // coefficients (exact), the channels assembled.
            Frame channels[3];
            for (int c = 0; c < 3; ++c) {
                const detail::MixedFrame grey = detail::mixMaterials(g, mSettings, c);
                RenderStats part;
                Renderer(grey.settings).renderGrid(*grey.grid, camera, passes, channels[c], part, progress);
                detail::addPartStats(stats, std::move(part), c == 0);
            }
            frame = detail::assembleChannels(channels);
            stats.warnings.push_back("volumes whose extinctions differ in hue (--add-volume-material): rendered once per channel, R, G "
                                     "and B, each medium grey at that channel's coefficients: exact, 3x the time");
        }
    };
    if (mSettings.threads > 0) {
        tbb::task_arena arena(mSettings.threads);
        arena.execute(run);
    } else {
        run();
    }
    progress.finish();
    if (!grid.isLevelSet() && movesOverTheShutter(g)) {
        if (std::string w = detail::longPathWarning(g, mSettings); !w.empty()) stats.warnings.push_back(std::move(w));
    }
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
