/// @file surface_rasterizer.cpp
#include "raster/surface_rasterizer.h"

#include "projection/projection.h"
#include "raster/tile_bins.h"
#include "support/blank_frame.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vdb_ewa {
namespace detail {
namespace {

/// Depth layers composited front to back per pixel: where a silhouette lies over another part
/// of the surface the front layer covers part of the pixel and the next the rest.
constexpr int kMaxLayers = 4;

/// Pair::r of a pair outside its footprint's cut-off: it may cover, and does not weigh.
constexpr double kNoWeight = std::numeric_limits<double>::infinity();

/// A (splat, tile pixel) pair where the pixel's centre lies inside the splat's cut-off or its
/// square meets the disc's box: its plane depth along the pixel's central ray, its conic
/// distance (kNoWeight outside the cut-off) and the pixel's subsamples its disc covers.
struct Pair
{
    double z;
    double r;
    std::uint32_t splat;
    int mask; ///< the subsamples its disc covers; -1: not computed yet (only needed until the
              ///< pixel is covered)
    bool shades; ///< the pixel lies on the kept side of the kernel's clip lines
};

} // namespace

SurfaceLayer rasterizeSurfaceLayer(const SurfaceSplatSet& set, const Camera& camera, const RenderSettings& settings,
    SurfaceStats& stats, Progress* progress, const MemoryBudget* budget)
{
    const int width = camera.width(), height = camera.height();
    SurfaceLayer layer;
    layer.width = width;
    layer.height = height;
    layer.rgba.assign(4 * std::size_t(width) * std::size_t(height), 0.0f);
    layer.depth.assign(std::size_t(width) * std::size_t(height), std::numeric_limits<float>::quiet_NaN());
    const LargeArray<SurfaceSplat>& splats = set.splats;
    stats.splats = std::size_t(std::count_if(splats.begin(), splats.end(), [](const SurfaceSplat& s) { return s.x0 <= s.x1; }));
    stats.culled = set.kernels - stats.splats;
    const TileBins bins = binSplats(splats, width, height, budget);
    stats.splatTilePairs = bins.indices.size();
    const double tolerance = settings.surface.tolerance * set.spacing;

    const int tiles = bins.tilesX * bins.tilesY;
    setUnits(progress, std::uint64_t(tiles));
    tbb::parallel_for(tbb::blocked_range<int>(0, tiles, 1), [&](const tbb::blocked_range<int>& range) {
        std::vector<std::uint32_t> order;
        std::vector<Pair> pairs, sorted;
        std::vector<std::uint8_t> pixelOf;
        std::uint32_t start[kTilePixels + 1];
        for (int t = range.begin(); t < range.end(); ++t) {
            const int x0 = (t % bins.tilesX) * kTileSize, y0 = (t / bins.tilesX) * kTileSize;
            const int w = std::min(kTileSize, width - x0), h = std::min(kTileSize, height - y0);
            order.assign(bins.indices.begin() + std::ptrdiff_t(bins.offsets[t]),
                bins.indices.begin() + std::ptrdiff_t(bins.offsets[t + 1]));
            // Pass 1: every (pixel, splat) pair inside a footprint's cut-off, with its plane depth
            // along the pixel's central ray, bucketed by pixel.
            pairs.clear();
            pixelOf.clear();
            for (std::uint32_t index : order) {
                const SurfaceSplat& s = splats[index];
                const int lx0 = std::max(s.x0 - x0, 0), lx1 = std::min(s.x1 - x0, w - 1);
                const int ly0 = std::max(s.y0 - y0, 0), ly1 = std::min(s.y1 - y0, h - 1);
                for (int ly = ly0; ly <= ly1; ++ly)
                    for (int lx = lx0; lx <= lx1; ++lx) {
                        const double px = x0 + lx + 0.5, py = y0 + ly + 0.5;
                        const double dx = px - s.cx, dy = py - s.cy;
                        const double r = s.qa * dx * dx + 2.0 * s.qb * dx * dy + s.qc * dy * dy;
                        // Inside the cut-off a pair weighs; outside it may still cover (its
                        // square meets the disc's box), with no weight.
                        const bool weighs = r < s.cutoff;
                        if (!weighs && !(px + 0.5 >= s.disc.box[0] && px - 0.5 <= s.disc.box[2] && py + 0.5 >= s.disc.box[1] &&
                                           py - 0.5 <= s.disc.box[3]))
                            continue;
                        // The tangent plane's depth along the pixel's ray, and whether the
                        // pixel lies on the kept side of the kernel's crease clips.
                        double dz = 0.0;
                        const bool hit = s.disc.depthOffset(px, py, dz);
                        const double z = hit ? std::clamp(s.depth + dz, s.depth - s.depthRange, s.depth + s.depthRange) : s.depth;
                        const bool shades = hit ? s.disc.keptSide(px, py) : s.disc.clipCount == 0;
                        pairs.push_back({z, weighs ? r : kNoWeight, index, -1, shades});
                        pixelOf.push_back(std::uint8_t(ly * kTileSize + lx));
                    }
            }
            std::fill(std::begin(start), std::end(start), 0u);
            for (std::uint8_t p : pixelOf) ++start[p + 1];
            for (int p = 0; p < kTilePixels; ++p) start[p + 1] += start[p];
            sorted.resize(pairs.size());
            {
                std::uint32_t next[kTilePixels];
                std::copy(std::begin(start), std::end(start) - 1, std::begin(next));
                for (std::size_t i = 0; i < pairs.size(); ++i) sorted[next[pixelOf[i]]++] = pairs[i];
            }
            // Pass 2, per pixel, its pairs front to back in depth layers: a layer's front is the
            // nearest pair whose disc covers a subsample not yet covered; the pairs within the
            // tolerance of it join the layer (Sec. 7.2's z-buffer with a tolerance). A layer's
            // colour is its normalised weighted sum (Sec. 7.2), spread over the subsamples it
            // newly covers. Discs are tested only until the pixel is covered.
            std::uint16_t covered[kTilePixels];
            double out[kTilePixels][3], depth[kTilePixels];
            for (int p = 0; p < kTilePixels; ++p) {
                covered[p] = 0;
                out[p][0] = out[p][1] = out[p][2] = 0.0;
                depth[p] = std::numeric_limits<double>::quiet_NaN();
                if (start[p] == start[p + 1]) continue;
                const auto first = sorted.begin() + std::ptrdiff_t(start[p]), last = sorted.begin() + std::ptrdiff_t(start[p + 1]);
                // Where every pair lies within the tolerance of the nearest, they are one layer
                // whatever their order (most pixels inside a surface): no sort.
                const auto [zMin, zMax] = std::minmax_element(first, last, [](const Pair& a, const Pair& b) { return a.z < b.z; });
                if (zMax->z - zMin->z > tolerance) {
                    std::sort(first, last, [](const Pair& a, const Pair& b) { return a.z < b.z || (a.z == b.z && a.splat < b.splat); });
                } else {
                    // The disc nearest the pixel first: it is the likeliest to cover all of it,
                    // and discs are then tested only until the pixel is covered.
                    std::iter_swap(first, std::min_element(first, last, [](const Pair& a, const Pair& b) { return a.r < b.r; }));
                }
                const double px = x0 + p % kTileSize + 0.5, py = y0 + p / kTileSize + 0.5;
                auto maskOf = [&](Pair& pair) {
                    if (pair.mask < 0) pair.mask = splats[pair.splat].disc.mask(px, py);
                    return std::uint16_t(pair.mask);
                };
                auto it = first;
                for (int layer = 0; layer < kMaxLayers && it != last && covered[p] != kAllSubsamples; ++layer) {
                    // The front: the nearest pair that adds coverage.
                    auto front = it;
                    while (front != last && (maskOf(*front) & ~covered[p]) == 0) ++front;
                    if (front == last) break;
                    const double limit = front->z + tolerance;
                    // Sums over the pairs that shade the pixel ([1]), over all ([0], where a
                    // crease leaves none: a pixel at the edge itself), and of all unweighted
                    // ([2], where the layer's discs reach past every footprint's cut-off).
                    double weight[3] = {0.0, 0.0, 0.0}, zSum[3] = {0.0, 0.0, 0.0}, colour[3][3] = {};
                    std::uint16_t layerMask = 0;
                    for (; it != last && it->z <= limit; ++it) {
                        const SurfaceSplat& s = splats[it->splat];
                        const double wt = it->r < kNoWeight ? double(s.weight * std::exp(float(-0.5 * it->r))) : 0.0;
                        const double wts[3] = {wt, it->shades ? wt : 0.0, 1.0};
                        for (int k = 0; k < 3; ++k) {
                            weight[k] += wts[k];
                            zSum[k] += wts[k] * it->z;
                            for (int c = 0; c < 3; ++c) colour[k][c] += wts[k] * s.colour[c];
                        }
                        if ((covered[p] | layerMask) != kAllSubsamples) layerMask = std::uint16_t(layerMask | maskOf(*it));
                    }
                    const std::uint16_t fresh = std::uint16_t(layerMask & ~covered[p]);
                    const int k = weight[1] > 0.0 ? 1 : weight[0] > 0.0 ? 0 : 2;
                    if (fresh == 0) continue;
                    const double share = double(__builtin_popcount(fresh)) / kSubsamples;
                    for (int c = 0; c < 3; ++c) out[p][c] += share * colour[k][c] / weight[k];
                    if (std::isnan(depth[p])) depth[p] = zSum[k] / weight[k];
                    covered[p] = std::uint16_t(covered[p] | fresh);
                }
            }
            for (int ly = 0; ly < h; ++ly)
                for (int lx = 0; lx < w; ++lx) {
                    const int p = ly * kTileSize + lx;
                    const std::size_t i = std::size_t(y0 + ly) * std::size_t(width) + std::size_t(x0 + lx);
                    for (int c = 0; c < 3; ++c) layer.rgba[4 * i + std::size_t(c)] = float(out[p][c]);
                    layer.rgba[4 * i + 3] = float(double(__builtin_popcount(covered[p])) / kSubsamples);
                    layer.depth[i] = float(depth[p]);
                }
            advance(progress);
        }
    });
    return layer;
}

Frame rasterizeSurfaces(const SurfaceSplatSet& set, const Camera& camera, const RenderSettings& settings,
    const PassRequest& passes, SurfaceStats& stats, Progress* progress, const MemoryBudget* budget)
{
    const SurfaceLayer layer = rasterizeSurfaceLayer(set, camera, settings, stats, progress, budget);
    Frame frame = blankFrame(layer.width, layer.height, passes);
    for (int y = 0; y < layer.height; ++y)
        for (int x = 0; x < layer.width; ++x) {
            const std::size_t i = std::size_t(y) * std::size_t(layer.width) + std::size_t(x);
            float* px = frame.beauty.pixel(x, y);
            for (int c = 0; c < 4; ++c) px[c] = layer.rgba[4 * i + std::size_t(c)];
            const float alpha = px[3];
            if (passes.depth && alpha >= 0.5f) frame.depth[i] = layer.depth[i];
            if (passes.transmittance) std::fill_n(&frame.transmittance[3 * i], 3, 1.0f - alpha);
        }
    return frame;
}

} // namespace detail
} // namespace vdb_ewa
