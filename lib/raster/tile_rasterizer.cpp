/// @file tile_rasterizer.cpp
/// @brief The volume rasteriser's order of work for a whole frame: the splats' sweep order and
///        their tiles, the options every tile shares, a slab compositor backend
///        (raster/slab_compositor.h), then the frame's deep image and counters.
#include "raster/tile_rasterizer.h"

#include "raster/frame_compositing.h"
#include "support/blank_frame.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vdb_ewa {
namespace detail {
namespace {

/// Splats whose optical depth and source terms are the same in R, G and B, lit by grey lights.
bool allGrey(const SplatSet& set, const CompositeOptions& options, const OpticalModel& model)
{
    const auto grey = [](const float* v) { return v[0] == v[1] && v[0] == v[2]; };
    const float ext[3] = {float(model.extinction(0)), float(model.extinction(1)), float(model.extinction(2))};
    if (!grey(ext)) return false;
    for (const CompositeLight& light : options.lights) {
        if (!grey(light.scale)) return false;
    }
    for (std::size_t i = 0; i < set.splats.size(); ++i) {
        const Splat& s = set.splats[i];
        if (!grey(s.tau) || !grey(s.emission) || !grey(s.scatter)) return false;
        for (int k = 0; k < set.passSourceCount; ++k) {
            if (!grey(&set.passSources[(i * std::size_t(set.passSourceCount) + std::size_t(k)) * 3])) return false;
        }
    }
    return true;
}

/// A splat's place in the sweep: its pixel box, slab span and index, gathered in sweep order
/// so that binning reads 24 bytes a splat in sequence instead of 96 in depth order.
struct SweepEntry
{
    int x0, y0, x1, y1;
    std::uint32_t span, index;
};

/// The order in which every tile sweeps its splats: by first slab, ties in kernel order (a
/// tile's list, binned in this order, needs no sort of its own). Sorted as 64-bit keys (first
/// slab above, kernel index below) where the slabs' range fits 32 bits.
std::vector<SweepEntry> sweepOrder(const SplatSet& set)
{
    const auto& splats = set.splats;
    const std::size_t n = splats.size();
    std::vector<std::uint32_t> order(n);
    std::int64_t lo = 0, hi = 0;
    if (n > 0) {
        lo = hi = splats[0].firstSlab;
        for (const Splat& s : splats) {
            lo = std::min(lo, s.firstSlab);
            hi = std::max(hi, s.firstSlab);
        }
    }
    if (std::uint64_t(hi - lo) < (std::uint64_t(1) << 32)) {
        std::vector<std::uint64_t> keys(n);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) keys[i] = (std::uint64_t(splats[i].firstSlab - lo) << 32) | i;
        });
        tbb::parallel_sort(keys.begin(), keys.end());
        for (std::size_t k = 0; k < n; ++k) order[k] = std::uint32_t(keys[k]);
    } else {
        for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
        tbb::parallel_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
            const std::int64_t sa = splats[a].firstSlab, sb = splats[b].firstSlab;
            return sa < sb || (sa == sb && a < b);
        });
    }
    std::vector<SweepEntry> entries(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const Splat& s = splats[order[k]];
            entries[k] = {s.x0, s.y0, s.x1, s.y1, s.slabCount, order[k]};
        }
    });
    return entries;
}

} // namespace

TileBins binInSweepOrder(const SplatSet& set, int width, int height, const MemoryBudget* budget)
{
    const std::vector<SweepEntry> sweep = sweepOrder(set);
    return binInOrder(
        sweep.size(), [&](std::size_t k) -> const SweepEntry& { return sweep[k]; }, [&](std::size_t k) { return sweep[k].index; },
        [&](std::size_t k) { return sweep[k].span; }, width, height, budget);
}

FrameCompositing::FrameCompositing(const Camera& camera, const RenderSettings& settings, const PassRequest& passes,
    const std::vector<LightMap>& lights, bool tinted, bool emissive, const SlabGrid& slabs, const PointLights* pointLights)
    : model(settings), table(float(settings.splat.cutoffRadius * settings.splat.cutoffRadius))
{
    options.cutoff = float(settings.cutoff);
    options.exp = settings.splat.expEvaluation;
    options.imageLod = float(settings.splat.imageLod);
    options.imageLodComposite = settings.splat.imageLodComposite;
    // exp(-r/2) at r = s.cutoff, in the float arithmetic the splats' cut-off is kept in.
    if (settings.splat.taper) options.taperEdge = std::exp(-0.5f * float(settings.splat.cutoffRadius * settings.splat.cutoffRadius));
    options.table = &table;
    options.slabs = slabs;
    options.passes = passes;
    options.layout = PassLayout(passes);
    for (std::size_t l = 0; l < lights.size(); ++l) {
        if (model.dark(l)) continue;
        CompositeLight light;
        light.map = &lights[l];
        for (int c = 0; c < 3; ++c) light.scale[c] = float(model.lightScale(l, c));
        light.towards = settings.lights[l].unitDirection();
        options.lights.push_back(light);
    }
    options.model = &model;
    options.camera = &camera;
    if (pointLights && !pointLights->empty()) options.pointLights = pointLights;
    options.tinted = tinted && options.lit();
    options.emissive = emissive;
}

std::unique_ptr<SlabCompositor> slabCompositorFor(const RenderSettings& settings, int channels, RasterStats& stats)
{
    std::unique_ptr<SlabCompositor> backend = settings.simd ? simdSlabCompositor(channels) : nullptr;
    stats.backend = backend ? simdTarget() : "scalar";
    if (!backend) backend = scalarSlabCompositor(channels);
    return backend;
}

void addCounters(const std::vector<TileCounters>& counters, RasterStats& stats)
{
    stats.tiles = std::uint64_t(counters.size());
    for (const TileCounters& c : counters) {
        stats.tilesOpaque += (c.skipped > 0);
        stats.pairsSkipped += c.skipped;
        stats.footprintSamples += c.samples;
        for (int k = 0; k < kImageLevels; ++k) stats.levelSamples[k] += c.levelSamples[k];
        stats.slabComposites += c.composites;
        for (int k = 0; k < kImageLevels; ++k) stats.levelComposites[k] += c.levelComposites[k];
    }
}

/// Camera depth per unit of distance along each pixel centre's ray: the cosine between the
/// ray and the viewing axis (perspective), 1 (orthographic).
std::vector<float> depthScales(const Camera& camera)
{
    const int width = camera.width(), height = camera.height();
    std::vector<float> scale;
    assignAdvised(scale, std::size_t(width) * std::size_t(height), 1.0f);
    if (camera.projection() != Projection::Perspective) return scale;
    const double f = camera.focalPixels();
    const Vec2d c = camera.principalPoint();
    tbb::parallel_for(tbb::blocked_range<int>(0, height, 16), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y)
            for (int x = 0; x < width; ++x) {
                const double u = (x + 0.5 - c.x) / f, v = (y + 0.5 - c.y) / f;
                scale[std::size_t(y) * std::size_t(width) + std::size_t(x)] = float(1.0 / std::sqrt(1.0 + u * u + v * v));
            }
    });
    return scale;
}

/// Tiles' deep samples -> one DeepImage in pixel order, depths converted to camera depth.
DeepImage assembleDeep(std::vector<TileDeep>& tiles, int tilesX, int width, int height, const std::vector<float>& depthScale)
{
    DeepImage deep;
    deep.width = width;
    deep.height = height;
    deep.offsets.assign(std::size_t(width) * std::size_t(height) + 1, 0);
    for (int t = 0; t < int(tiles.size()); ++t) {
        const int x0 = (t % tilesX) * kTileSize, y0 = (t / tilesX) * kTileSize;
        for (int p = 0; p < kTilePixels; ++p) {
            const int x = x0 + p % kTileSize, y = y0 + p / kTileSize;
            if (x < width && y < height) deep.offsets[std::size_t(y) * std::size_t(width) + std::size_t(x) + 1] = tiles[std::size_t(t)].counts[p];
        }
    }
    for (std::size_t i = 1; i < deep.offsets.size(); ++i) deep.offsets[i] += deep.offsets[i - 1];
    deep.samples.resize(deep.offsets.back());
    tbb::parallel_for(tbb::blocked_range<int>(0, int(tiles.size())), [&](const tbb::blocked_range<int>& range) {
        for (int t = range.begin(); t < range.end(); ++t) {
            TileDeep& tile = tiles[std::size_t(t)];
            const int x0 = (t % tilesX) * kTileSize, y0 = (t / tilesX) * kTileSize;
            std::size_t next = 0;
            for (int p = 0; p < kTilePixels; ++p) {
                const int x = x0 + p % kTileSize, y = y0 + p / kTileSize;
                const std::size_t i = std::size_t(y) * std::size_t(width) + std::size_t(x);
                for (std::uint32_t k = 0; k < tile.counts[p]; ++k, ++next) {
                    DeepSample d = tile.samples[next];
                    d.z *= depthScale[i];
                    d.zBack *= depthScale[i];
                    deep.samples[deep.offsets[i] + k] = d;
                }
            }
            tile.samples = {};
        }
    });
    return deep;
}

Frame rasterizeSplats(const SplatSet& set, const Camera& camera, const RenderSettings& settings,
    const PassRequest& passes, RasterStats& stats, const std::vector<LightMap>& lights, bool tinted, Progress* progress,
    const MemoryBudget* budget, const SurfaceLayer* surface, const SurfaceLayer* surfaceShadow, const PointLights* pointLights)
{
    const int width = camera.width(), height = camera.height();
    Frame frame = blankFrame(width, height, passes);

    const TileBins bins = binInSweepOrder(set, width, height, budget);
    stats.splatTilePairs = bins.indices.size();
    const int tiles = bins.tilesX * bins.tilesY;
    std::vector<TileCounters> counters(static_cast<std::size_t>(tiles));
    const bool emissive = std::any_of(set.splats.begin(), set.splats.end(),
        [](const Splat& s) { return s.emission[0] != 0.0f || s.emission[1] != 0.0f || s.emission[2] != 0.0f; });
    FrameCompositing compositing(camera, settings, passes, lights, tinted, emissive, set.slabs, pointLights);
    CompositeOptions& options = compositing.options;
    // Motion blur: the light looked up where each sample's material came from (the whole
    // frame's maps are marched whole: no lookup box to pad, maxShift unused).
    options.shifted = !set.shifts.empty();
    // Motion blur's shutter layers, where some splat covers only some of them (a deep image
    // keeps one: its samples are the slabs' own).
    const bool layered = std::any_of(set.splats.begin(), set.splats.end(), [](const Splat& s) { return s.layerCount != 0; });
    options.layers = layered && !passes.deep ? settings.motionBlur.layers : 1;
    const std::vector<float> depthScale = (passes.depth || passes.deep || surface) ? depthScales(camera) : std::vector<float>{};
    // The surface's slab coordinate per pixel: its camera depth along the pixel's ray.
    std::vector<float> surfaceAt;
    if (surface) {
        surfaceAt.resize(surface->depth.size());
        for (std::size_t i = 0; i < surfaceAt.size(); ++i) surfaceAt[i] = surface->depth[i] / depthScale[i];
        options.surface = surface;
        options.surfaceAt = surfaceAt.data();
        options.surfaceShadow = surfaceShadow;
    }
    std::vector<TileDeep> deep(passes.deep ? std::size_t(tiles) : 0);
    setUnits(progress, std::uint64_t(bins.tilesX) * std::uint64_t(bins.tilesY));
    // A surface keeps the one-channel path where its colours (and the shadow pass's) are grey.
    const auto grey = [](const SurfaceLayer* layer) {
        if (!layer) return true;
        for (std::size_t i = 0; i < layer->rgba.size(); i += 4) {
            if (layer->rgba[i] != layer->rgba[i + 1] || layer->rgba[i] != layer->rgba[i + 2]) return false;
        }
        return true;
    };
    const int channels = allGrey(set, options, compositing.model) && grey(surface) && grey(surfaceShadow) ? 1 : 3;
    const std::unique_ptr<SlabCompositor> backend = slabCompositorFor(settings, channels, stats);
    backend->composite(set, bins, options, depthScale, frame, deep, counters, progress);
    if (passes.deep) frame.deep = assembleDeep(deep, bins.tilesX, width, height, depthScale);
    addCounters(counters, stats);
    return frame;
}

} // namespace detail
} // namespace vdb_ewa
