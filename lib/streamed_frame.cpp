/// @file streamed_frame.cpp
/// @brief The streamed frame (--cull on): bricks front to back in depth windows, each window's
///        bricks expanded, projected, lit on demand and composited through the stages' doors,
///        those behind opaque tiles never expanded (docs/architecture.md#the-streamed-frame).
///        Sub-frames (motion blur's parts of the shutter, depth of field's parts of the lens)
///        share one sweep: each window's bricks are expanded, and the light marched, once for all.
#include <vdb_ewa/renderer.h>

#include "frame_lights.h"
#include "frame_parts.h"
#include "projection/projection.h"
#include "raster/raster.h"
#include "shading/shading.h"
#include "source/source.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

namespace vdb_ewa {

using detail::StageTimer;

namespace {

/// One sub-frame of the streamed frame: its part of the shutter and of the lens, the bounds of
/// the bricks through its camera, its raster, and the splats it carries to the next window.
struct StreamedView
{
    StreamedView(RenderSettings s, Camera c) : settings(std::move(s)), camera(std::move(c)) {}

    RenderSettings settings;
    Camera camera;
    std::vector<detail::BrickBounds> bounds;
    std::unique_ptr<detail::StreamedRaster> raster;
    detail::SplatSet carried;
    int deferred = 0;
    std::int64_t windowStart = std::numeric_limits<std::int64_t>::min();
};

} // namespace

void Renderer::renderStreamedFogVolume(const GridSource::Impl& g, const Camera& camera, const PassRequest& passes, Frame& frame,
    RenderStats& stats, detail::Progress& progress) const
{
    StageTimer timer;
    progress.stage(0, 5);
    const detail::MemoryBudget budget = detail::budgetFor(g, mSettings);
    const std::vector<detail::Brick> bricks = detail::listBricks(g);
    // The slabs every window shares: --slab thick, unless some kernel could span more than
    // kSlabSpanTarget of them (the whole frame raises the thickness from the kernels it made;
    // it renders those grids). A lens part's pinhole moves in the lens plane: its depths, and so
    // its slabs, are the whole lens's. Tiles seen small coarsen within them.
    const SlabGrid slabs = detail::frameSlabs(g, camera, mSettings);
    const detail::LevelOfDetail lod(g, camera, mSettings, detail::widestLatticeSpacing(g, slabs, mSettings));
    {
        int widest = mSettings.splat.lodPixels > 0.0 ? detail::LevelOfDetail::kLeafDim : 1;
        for (const detail::Brick& b : bricks) {
            if (!b.leaf) widest = std::max(widest, detail::tileLattice(b.box, mSettings.splat.tileKernelSpacing, &lod).widest());
        }
        if (detail::slabsSpanned(g, slabs, mSettings, widest) > double(detail::kSlabSpanTarget)) return;
    }
    // The sub-frames (Renderer::renderSubFrames): sub-frame s of n takes the shutter's part s and
    // the lens's part s. Each holds an image of its own; where n images do not fit in half the
    // budget, renderSubFrames renders them one after the other.
    const MotionBlur& blur = mSettings.motionBlur;
    const bool moving = movesOverTheShutter(g) && blur.samples > 1, lens = camera.lensRadius() > 0.0 && mSettings.lensSamples > 1;
    const int n = detail::subFrameCount(mSettings, moving, lens, passes.deep);
    const double pixels = double(camera.width()) * double(camera.height());
    if (n > 1 && double(n) * pixels > budget.itemsWithin(0.5, detail::kBytesPerPixel)) return;
    std::vector<std::unique_ptr<StreamedView>> views;
    for (int s = 0; s < n; ++s) {
        RenderSettings part = n > 1 ? detail::subFrameSettings(mSettings, moving, s, n) : mSettings;
        views.push_back(std::make_unique<StreamedView>(std::move(part), lens ? camera.throughLensPart(s, n) : camera));
    }
    stats.streamed = true;
    stats.bricks = bricks.size();
    stats.activeVoxels = g.activeVoxels;
    stats.activeTiles = g.activeTiles;

    // Every brick's screen rectangle and first slab through each sub-frame's camera, before any
    // kernel exists (the whole shutter's travel pads every sub-frame's bounds).
    std::vector<std::int64_t> nearestSlab(bricks.size(), std::numeric_limits<std::int64_t>::max());
    std::vector<char> visible(bricks.size(), 0);
    for (const auto& view : views) {
        const detail::BrickBounder bounder(g, view->camera, mSettings, &lod, slabs);
        view->bounds.resize(bricks.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, bricks.size()), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) view->bounds[i] = bounder.bound(bricks[i]);
        });
        for (std::size_t i = 0; i < bricks.size(); ++i) {
            if (!view->bounds[i].visible) continue;
            visible[i] = 1;
            nearestSlab[i] = std::min(nearestSlab[i], view->bounds[i].nearestSlab);
        }
    }
    // Front to back: by first slab, ties in tree order.
    std::vector<std::uint32_t> order;
    double voxels = 0.0;
    for (std::uint32_t i = 0; i < bricks.size(); ++i) {
        if (!visible[i]) continue;
        order.push_back(i);
        voxels += bricks[i].leaf ? double(bricks[i].leaf->onVoxelCount()) : double(bricks[i].box.volume());
    }
    stats.bricksOutside = bricks.size() - order.size();
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return nearestSlab[a] < nearestSlab[b]; });
    stats.kernelSeconds += timer.lap();

    // Light on demand: no ray is marched yet; the compositor marches those its lookups read,
    // once for every sub-frame (the light follows the shutter's mid-time; it knows no camera).
    // Point and spot lights: their maps marched whole, then looked up as the light on demand's.
    // A Scene's renders take the maps an earlier one made, with the rays it marched.
    detail::FrameLights frameLights;
    detail::frameLights(frameLights, mSettings, g, budget, progress, stats, true, mLightCache);
    const std::vector<detail::LightMap>& lights = *frameLights.maps;
    const detail::PointLights& pointLights = *frameLights.points;
    stats.shadowSeconds = timer.lap();

    progress.stage(5, 100);
    progress.setUnits(order.size());
    progress.advance(0); // the windows' start is reported (the first window may take a while)
    for (const auto& view : views) {
        view->raster = std::make_unique<detail::StreamedRaster>(view->camera, view->settings, passes, lights, g.color != nullptr,
            detail::greyFrame(mSettings, g), slabs, &budget, &pointLights,
            view->settings.motionBlur.lightFollows ? detail::largestTravel(g, view->settings) : 0.0,
            movesOverTheShutter(g) ? view->settings.motionBlur.layers : 1);
    }
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
    const double tiles = double(views.front()->raster->tilesX()) * double(views.front()->raster->tilesY());
    constexpr double kCrossingShare = 0.5, kLargeSplatTiles = 64.0;
    constexpr int kMaxDeferred = 2;
    detail::MotionStats motion;
    std::uint64_t outOfOrder = 0, beforeNear = 0, clampedNear = 0, clampedGrazing = 0, clippedSpan = 0, notANumber = 0, clamped = 0;
    for (std::size_t begin = 0; begin < order.size();) {
        // The window: bricks up to about windowVoxels, ending between two first slabs.
        std::size_t end = begin;
        double held = 0.0;
        while (end < order.size() && (held < windowVoxels || nearestSlab[order[end]] == nearestSlab[order[end - 1]])) {
            const detail::Brick& b = bricks[order[end++]];
            held += b.leaf ? double(b.leaf->onVoxelCount()) : double(b.box.volume());
        }
        const std::int64_t windowEnd = end < order.size() ? nearestSlab[order[end]] : std::numeric_limits<std::int64_t>::max();
        ++stats.windows;
        // Bricks whose every tile is opaque already in every sub-frame are never expanded (the
        // occlusion summary).
        std::vector<const detail::Brick*> expanded;
        for (std::size_t k = begin; k < end; ++k) {
            const bool hidden = std::all_of(views.begin(), views.end(), [&](const auto& view) {
                const detail::BrickBounds& b = view->bounds[order[k]];
                return !b.visible ||
                       view->raster->hidden(b.x0 / detail::kTileSize, b.y0 / detail::kTileSize, b.x1 / detail::kTileSize, b.y1 / detail::kTileSize);
            });
            if (hidden) {
                ++stats.bricksHidden;
                continue;
            }
            expanded.push_back(&bricks[order[k]]);
        }
        stats.bricksExpanded += expanded.size();
        // The window's kernels, once for every sub-frame.
        detail::KernelSet kernels;
        std::vector<detail::Rgb> colors;
        std::vector<Vec3d> velocities;
        if (!expanded.empty()) {
            kernels = detail::extractKernels(g, mSettings, &lod, nullptr, &budget, nullptr, &expanded);
            if (alpha > 0.0) stats.haloKernels += detail::quasiInterpolate(g, alpha, kernels, nullptr, &units);
            stats.kernels += kernels.kernels.size();
            stats.kernelsSkipped += kernels.belowCutoff + kernels.notANumber;
            notANumber += kernels.notANumber;
            clamped += kernels.clamped;
            stats.voxelsMerged += kernels.mergedVoxels;
            stats.mergedKernels += kernels.mergedKernels;
            colors = detail::kernelColors(g, kernels, mSettings.inputToWorking);
            if (movesOverTheShutter(g)) velocities = detail::kernelVelocities(g, kernels);
        }
        stats.kernelSeconds += timer.lap();
        for (std::size_t v = 0; v < views.size(); ++v) {
            StreamedView& view = *views[v];
            // The sub-frame's splats: the window's kernels moved over its part of the shutter and
            // seen through its part of the lens, then those earlier windows made for it (carried).
            detail::SplatSet window;
            if (!expanded.empty()) {
                const bool last = v + 1 == views.size();
                detail::KernelSet moved;
                std::vector<detail::Rgb> movedColors;
                if (last) {
                    moved = std::move(kernels);
                    movedColors = std::move(colors);
                } else {
                    moved = kernels;
                    movedColors = colors;
                }
                const detail::MotionStats m = detail::moveKernels(g, view.settings, view.camera, moved, movedColors, &budget, velocities.empty() ? nullptr : &velocities);
                // The moving kernels and the warnings are each sub-frame's alike; sub-kernels add up.
                stats.motionSubKernels += m.subKernels;
                if (v == 0) {
                    stats.movingKernels += m.moving;
                    motion.clamped += m.clamped;
                    motion.longPaths += m.longPaths;
                }
                // Counted once for each sub-frame that splats them (the first's were counted above).
                stats.kernels += v == 0 ? m.subKernels : moved.kernels.size();
                stats.kernelSeconds += timer.lap();
                window = detail::projectSplats(g, moved, movedColors, view.camera, view.settings, passes, nullptr, &slabs);
                stats.kernelsCulled += window.culled;
                stats.splats += window.splats.size();
                beforeNear += window.beforeNear;
                clampedNear += window.clampedNear;
                clampedGrazing += window.clampedGrazing;
                clippedSpan += window.clippedSpan;
                for (const detail::Splat& sp : window.splats) outOfOrder += sp.firstSlab < view.windowStart;
            }
            detail::appendSplats(window, view.carried);
            stats.splatsInFlight = std::max<std::uint64_t>(stats.splatsInFlight, window.splats.size());
            stats.projectSeconds += timer.lap();
            // Ending a window here leaves the slabs of the splats crossing its end pending in
            // every tile they cover, copied aside until the next window. Where a few large splats
            // (near the eye) cross it over most of the image, the window goes on into the next,
            // up to kMaxDeferred times (culling needs windows to end): pig's first windows, 200
            // MB of pending slabs at 1080p, 0.5 s in page faults (docs/performance.md).
            double crossing = 0.0, crossingSplats = 0.0;
            for (const detail::Splat& sp : window.splats) {
                if (sp.firstSlab + std::int64_t(sp.slabCount) <= windowEnd) continue;
                crossing += double(sp.x1 / detail::kTileSize - sp.x0 / detail::kTileSize + 1) * double(sp.y1 / detail::kTileSize - sp.y0 / detail::kTileSize + 1);
                crossingSplats += 1.0;
            }
            if (crossing > kCrossingShare * tiles && crossing > kLargeSplatTiles * crossingSplats && view.deferred < kMaxDeferred && end < order.size()) {
                ++view.deferred;
                view.carried = std::move(window);
            } else {
                view.deferred = 0;
                view.carried = detail::splitSplatsAt(window, windowEnd);
                stats.rasterSeconds += timer.lap();
                view.raster->composite(window, windowEnd, &progress); // marches the light its live pixels look up
                view.windowStart = windowEnd;
            }
            stats.rasterSeconds += timer.lap();
        }
        progress.advance(end - begin);
        begin = end;
        windowVoxels = std::min(windowVoxels * kGrowth, mostVoxels);
        // Where three windows and an eighth of the voxels left fewer than kFewOpaque of the tiles
        // opaque (in every sub-frame), little will be hidden: the rest in as few windows as the
        // budget allows. (A window composites only in front of the next one's first slab, a
        // brick's reach in front of its voxels: the first window may composite nothing yet.)
        done += held;
        const bool fewOpaque = std::all_of(views.begin(), views.end(), [&](const auto& view) { return double(view->raster->opaqueTiles()) < kFewOpaque * tiles; });
        if (stats.windows >= 3 && done >= voxels / 8.0 && fewOpaque) windowVoxels = mostVoxels;
    }
    // The sub-frames' images averaged (detail::addToAverage); their rasters' counters summed.
    detail::RasterStats rasterStats;
    for (std::size_t v = 0; v < views.size(); ++v) {
        detail::RasterStats own;
        detail::addToAverage(frame, views[v]->raster->finish(own), int(v), n);
        views[v]->raster.reset();
        rasterStats.splatTilePairs += own.splatTilePairs;
        rasterStats.pairsSkipped += own.pairsSkipped;
        rasterStats.footprintSamples += own.footprintSamples;
        for (int k = 0; k < detail::kImageLevels; ++k) rasterStats.levelSamples[k] += own.levelSamples[k];
        rasterStats.slabComposites += own.slabComposites;
        for (int k = 0; k < detail::kImageLevels; ++k) rasterStats.levelComposites[k] += own.levelComposites[k];
        if (v == 0) {
            rasterStats.tiles = own.tiles;
            rasterStats.tilesOpaque = own.tilesOpaque;
            rasterStats.backend = own.backend;
        }
    }
    stats.rasterSeconds += timer.lap();
    detail::addRasterStats(rasterStats, stats);
    detail::addLightStats(frameLights, stats);
    if (outOfOrder) stats.warnings.push_back(detail::countLine(outOfOrder, "splats started in front of their window (a bound of the streamed frame is wrong; --cull off renders without it)"));
    if (g.activeVoxels == 0 && g.activeTiles == 0) stats.warnings.push_back("the grid has no active values: the image is empty");
    // Counted in the bricks expanded: a hidden brick's values are never read.
    detail::valueWarnings(notANumber, clamped, stats.warnings);
    detail::motionWarnings(motion, mSettings.motionBlur.splitSigmas, stats.warnings);
    detail::splatWarnings(beforeNear, clampedNear, clampedGrazing, clippedSpan, stats.warnings);
}

} // namespace vdb_ewa
