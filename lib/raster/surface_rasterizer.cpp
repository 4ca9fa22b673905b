/// @file surface_rasterizer.cpp
#include "raster/surface_rasterizer.h"

#include "projection/projection.h"
#include "raster/disc_coverage.h"
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

/// A projected, shaded surface kernel.
struct SurfaceSplat
{
    float cx, cy;          ///< centre, raster
    float qa, qb, qc;      ///< conic, 1/pixels^2
    float cutoff;          ///< the filtered footprint: weights where d^T Q d < cutoff
    float reach;           ///< pixels whose square may meet the disc: d^T Q d < reach (>= cutoff)
    float weight;          ///< area x footprint peak
    float colour[3];       ///< shaded colour
    double depth;          ///< camera depth of the centre
    DiscCoverage disc;     ///< the kernel's disc in its tangent plane, seen from the camera
    double depthRange;     ///< plane depths along a ray are clamped to depth +- this: the disc
                           ///< and two pixels' width (the filtered footprint reaches that far)
    int x0, y0, x1, y1;
};

/// A (splat, tile pixel) pair inside the splat's reach: its plane depth along the pixel's
/// central ray, its conic distance and the pixel's subsamples its disc covers.
struct Pair
{
    double z;
    double r;
    std::uint32_t splat;
    int mask; ///< the subsamples its disc covers; -1: not computed yet (only needed until the
              ///< pixel is covered)
    bool shades; ///< the pixel lies on the kept side of the kernel's clip lines
};

/// vdb_render's shaders (RayTracer.h) with a white material (multiplied by the kernel's albedo).
Vec3d shade(SurfaceShader shader, const Vec3d& normal, const Vec3d& rayDir, const Vec3d& p, const SurfaceSet& set)
{
    switch (shader) {
    case SurfaceShader::Diffuse: return Vec3d(std::abs(glm::dot(normal, rayDir)));
    case SurfaceShader::Matte: return Vec3d(1.0);
    case SurfaceShader::Normal: return 0.5 * (normal + 1.0);
    case SurfaceShader::Position: {
        const Vec3d size = set.boundsMax - set.boundsMin;
        return Vec3d(size.x > 0 ? (p.x - set.boundsMin.x) / size.x : 0.0, size.y > 0 ? (p.y - set.boundsMin.y) / size.y : 0.0,
            size.z > 0 ? (p.z - set.boundsMin.z) / size.z : 0.0);
    }
    }
    return Vec3d(1.0);
}

std::vector<SurfaceSplat> projectSurfaceSplats(const SurfaceSet& set, const Camera& camera, const RenderSettings& settings)
{
    const ProjectionParams params = projectionParams(camera, settings.splat);
    const Vec3d forward = glm::transpose(camera.cameraFromWorld())[2];
    const bool perspective = params.perspective;
    const std::size_t n = set.kernels.size();
    std::vector<SurfaceSplat> splats(n);
    std::vector<std::uint8_t> visible(n, 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const SurfaceKernel& k = set.kernels[i];
            // Back faces are culled: that keeps thin parts from mixing both sides.
            Vec3d t, normal;
            Footprint fp;
            if (!projectSurface(k, set.sigma, camera, params, t, normal, fp)) continue;
            SurfaceSplat& s = splats[i];
            // Coverage is sampled across each pixel's square: every pixel whose square meets
            // the disc (inside the kernel's 3 sigma ellipse, so inside the filtered footprint's)
            // is visited, also where its centre lies outside the footprint's cut-off.
            const double radius = std::max(params.cutoffRadius, kDiscRadiusSigmas);
            const double qMax = 0.5 * (fp.conic.xx + fp.conic.yy) +
                std::sqrt(0.25 * (fp.conic.xx - fp.conic.yy) * (fp.conic.xx - fp.conic.yy) + fp.conic.xy * fp.conic.xy);
            const double reach = radius + std::sqrt(0.5 * qMax); // half a pixel diagonal in the conic's metric
            Footprint box = fp;
            box.halfExtent = fp.halfExtent * (radius / params.cutoffRadius) + Vec2d(0.5);
            if (!pixelBox(box, camera.width(), camera.height(), s.x0, s.y0, s.x1, s.y1)) continue;
            setFootprint(s, fp, params.cutoffRadius);
            s.reach = float(reach * reach);
            s.weight = float(k.area * fp.peak);
            const Vec3d rayDir = perspective ? glm::normalize(k.pWorld - camera.eye()) : forward;
            const Vec3d c = k.albedo * shade(settings.surface.shader, k.normal, rayDir, k.pWorld, set);
            for (int ch = 0; ch < 3; ++ch) s.colour[ch] = float(c[ch]);
            s.depth = t.z;
            const double disc = k.discRadius;
            Vec3d clipDirections[3];
            double clipDistances[3];
            for (int c = 0; c < k.clipCount; ++c) {
                clipDirections[c] = camera.cameraFromWorld() * Vec3d(k.clips[std::size_t(c)].direction);
                clipDistances[c] = double(k.clips[std::size_t(c)].distance);
            }
            s.disc = discCoverage(t, normal, disc, clipDirections, clipDistances, k.clipCount, camera);
            s.depthRange = disc + 2.0 * (perspective ? t.z : 1.0) / camera.focalPixels();
            visible[i] = 1;
        }
    });
    std::vector<SurfaceSplat> out;
    out.reserve(std::size_t(std::count(visible.begin(), visible.end(), 1)));
    for (std::size_t i = 0; i < n; ++i) {
        if (visible[i]) out.push_back(splats[i]);
    }
    return out;
}

} // namespace

Frame rasterizeSurfaces(const SurfaceSet& set, const Camera& camera, const RenderSettings& settings,
    const PassRequest& passes, SurfaceStats& stats, Progress* progress, const MemoryBudget* budget)
{
    const int width = camera.width(), height = camera.height();
    Frame frame = blankFrame(width, height, passes);

    const std::vector<SurfaceSplat> splats = projectSurfaceSplats(set, camera, settings);
    stats.splats = splats.size();
    stats.culled = set.kernels.size() - splats.size();
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
                        if (!(r < s.reach)) continue;
                        int mask = -1;
                        if (!(r < s.cutoff)) {
                            mask = s.disc.mask(px, py);
                            if (mask == 0) continue; // neither weight nor coverage
                        }
                        // The tangent plane's depth along the pixel's ray, and whether the
                        // pixel lies on the kept side of the kernel's crease clips.
                        Vec3d offset;
                        const bool hit = s.disc.planeOffset(px, py, offset);
                        const double z = hit ? std::clamp(s.depth + offset.z, s.depth - s.depthRange, s.depth + s.depthRange) : s.depth;
                        const bool shades = hit ? s.disc.keptSide(offset) : s.disc.clipCount == 0;
                        pairs.push_back({z, r, index, mask, shades});
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
                std::sort(first, last, [](const Pair& a, const Pair& b) { return a.z < b.z || (a.z == b.z && a.splat < b.splat); });
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
                    // Sums over the pairs that shade the pixel ([1]) and over all ([0], where a
                    // crease leaves none: a pixel at the edge itself).
                    double weight[2] = {0.0, 0.0}, zSum[2] = {0.0, 0.0}, colour[2][3] = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
                    std::uint16_t layerMask = 0;
                    for (; it != last && it->z <= limit; ++it) {
                        const SurfaceSplat& s = splats[it->splat];
                        const double wt = s.weight * std::exp(-0.5 * it->r);
                        for (int k = 0; k < (it->shades ? 2 : 1); ++k) {
                            weight[k] += wt;
                            zSum[k] += wt * it->z;
                            for (int c = 0; c < 3; ++c) colour[k][c] += wt * s.colour[c];
                        }
                        if ((covered[p] | layerMask) != kAllSubsamples) layerMask = std::uint16_t(layerMask | maskOf(*it));
                    }
                    const std::uint16_t fresh = std::uint16_t(layerMask & ~covered[p]);
                    const int k = weight[1] > 0.0 ? 1 : 0;
                    if (fresh == 0 || !(weight[k] > 0.0)) continue;
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
                    const double alpha = double(__builtin_popcount(covered[p])) / kSubsamples;
                    float* px = frame.beauty.pixel(x0 + lx, y0 + ly);
                    for (int c = 0; c < 3; ++c) px[c] = float(out[p][c]);
                    px[3] = float(alpha);
                    if (passes.depth && alpha >= 0.5) frame.depth[i] = float(depth[p]);
                    if (passes.transmittance) std::fill_n(&frame.transmittance[3 * i], 3, float(1.0 - alpha));
                }
            advance(progress);
        }
    });
    return frame;
}

} // namespace detail
} // namespace vdb_ewa
