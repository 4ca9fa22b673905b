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

/// The weights' cut-off in standard deviations of the filtered footprint (at most
/// --cutoff-radius). The colour is the weights' normalised sum, and coverage comes from the discs.
constexpr double kSurfaceCutoffRadius = 2.0;

/// A projected, shaded surface kernel.
struct SurfaceSplat
{
    float cx, cy;          ///< centre, raster
    float qa, qb, qc;      ///< conic, 1/pixels^2
    float cutoff;          ///< the filtered footprint: weights where d^T Q d < cutoff
    float weight;          ///< area x footprint peak
    float colour[3];       ///< shaded colour
    double depth;          ///< camera depth of the centre
    DiscCoverage disc;     ///< the kernel's disc in its tangent plane, seen from the camera
    double depthRange;     ///< plane depths along a ray are clamped to depth +- this: the disc
                           ///< and two pixels' width (the filtered footprint reaches that far)
    int x0, y0, x1, y1;
};

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

/// Projects kernel @a k, facing the eye with camera-space centre @a t and @a normal (facesEye),
/// into @a s: false where it is not drawn (outside the frame). The pixels visited are those whose centre lies in the footprint's cut-off (the
/// weights) or whose square meets the disc's raster box (coverage is sampled across each
/// pixel's square).
bool projectSurfaceSplat(const SurfaceKernel& k, const Vec3d& t, const Vec3d& normal, const SurfaceSet& set, const Camera& camera,
    const ProjectionParams& params, SurfaceShader shader, const Mat3d& inputToWorking, const Rgb* colour, SurfaceSplat& s)
{
    Footprint fp;
    if (!projectSurface(t, normal, set.sigma, params, fp)) return false;
    Vec3d clipDirections[3];
    double clipDistances[3];
    for (int l = 0; l < k.clipCount; ++l) {
        clipDirections[l] = camera.cameraFromWorld() * Vec3d(k.clips[std::size_t(l)].direction);
        clipDistances[l] = double(k.clips[std::size_t(l)].distance);
    }
    s.disc = discCoverage(t, normal, k.discRadius, clipDirections, clipDistances, k.clipCount, camera);
    // The union of the cut-off's box and the disc's box widened by half a pixel.
    const double* b = s.disc.box;
    const double lo[2] = {std::min(fp.centre.x - fp.halfExtent.x, b[0] - 0.5), std::min(fp.centre.y - fp.halfExtent.y, b[1] - 0.5)};
    const double hi[2] = {std::max(fp.centre.x + fp.halfExtent.x, b[2] + 0.5), std::max(fp.centre.y + fp.halfExtent.y, b[3] + 0.5)};
    Footprint box = fp;
    box.centre = 0.5 * Vec2d(lo[0] + hi[0], lo[1] + hi[1]);
    box.halfExtent = 0.5 * Vec2d(hi[0] - lo[0], hi[1] - lo[1]);
    if (!std::isfinite(box.centre.x + box.centre.y + box.halfExtent.x + box.halfExtent.y)) box = fp; // a disc through the eye plane
    if (!pixelBox(box, camera.width(), camera.height(), s.x0, s.y0, s.x1, s.y1)) return false;
    setFootprint(s, fp, params.cutoffRadius);
    s.weight = float(k.area * fp.peak);
    if (colour) {
        for (int ch = 0; ch < 3; ++ch) s.colour[ch] = (*colour)[std::size_t(ch)];
    } else {
        const Vec3d rayDir = params.perspective ? glm::normalize(k.pWorld - camera.eye()) : glm::transpose(camera.cameraFromWorld())[2];
        // vdb_render's material colour times its shader, in the input space (as it writes them).
        const Vec3d c = workingColor(inputToWorking, k.albedo * shade(shader, k.normal, rayDir, k.pWorld, set));
        for (int ch = 0; ch < 3; ++ch) s.colour[ch] = float(c[ch]);
    }
    s.depth = t.z;
    s.depthRange = k.discRadius + 2.0 * (params.perspective ? t.z : 1.0) / camera.focalPixels();
    return true;
}

/// The splats of the kernels facing the eye, in the kernels' order; those outside the frame
/// have an empty pixel box (x1 < x0). Only the kernels facing the eye take memory.
LargeArray<SurfaceSplat> projectSurfaceSplats(const SurfaceSet& set, const Camera& camera, const RenderSettings& settings,
    const std::vector<Rgb>* colours)
{
    ProjectionParams params = projectionParams(camera, settings.splat);
    params.cutoffRadius = std::min(params.cutoffRadius, kSurfaceCutoffRadius);
    params.taper = false; // surface splats are weight-normalised per pixel (Sec. 7.2): their edge is not tapered
    const std::size_t n = set.kernels.size();
    constexpr std::size_t kChunk = 4096;
    const std::size_t chunks = (n + kChunk - 1) / kChunk;
    std::vector<std::size_t> firstOfChunk(chunks + 1, 0);
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
        Vec3d t, normal;
        std::size_t count = 0;
        for (std::size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) count += facesEye(set.kernels[i], camera, t, normal) ? 1 : 0;
        firstOfChunk[c + 1] = count;
    });
    for (std::size_t c = 0; c < chunks; ++c) firstOfChunk[c + 1] += firstOfChunk[c];
    LargeArray<SurfaceSplat> splats(firstOfChunk[chunks]);
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
        std::size_t next = firstOfChunk[c];
        Vec3d t, normal;
        for (std::size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) {
            if (!facesEye(set.kernels[i], camera, t, normal)) continue;
            SurfaceSplat& s = splats[next++];
            if (!projectSurfaceSplat(set.kernels[i], t, normal, set, camera, params, settings.surface.shader, settings.inputToWorking, colours ? &(*colours)[i] : nullptr, s)) {
                s.x0 = s.y0 = 0;
                s.x1 = s.y1 = -1;
            }
        }
    });
    return splats;
}

} // namespace

SurfaceLayer rasterizeSurfaceLayer(const SurfaceSet& set, const Camera& camera, const RenderSettings& settings,
    SurfaceStats& stats, Progress* progress, const MemoryBudget* budget, const std::vector<Rgb>* colours)
{
    const int width = camera.width(), height = camera.height();
    SurfaceLayer layer;
    layer.width = width;
    layer.height = height;
    layer.rgba.assign(4 * std::size_t(width) * std::size_t(height), 0.0f);
    layer.depth.assign(std::size_t(width) * std::size_t(height), std::numeric_limits<float>::quiet_NaN());
    const LargeArray<SurfaceSplat> splats = projectSurfaceSplats(set, camera, settings, colours);
    stats.splats = std::size_t(std::count_if(splats.begin(), splats.end(), [](const SurfaceSplat& s) { return s.x0 <= s.x1; }));
    stats.culled = set.kernels.size() - stats.splats;
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

Frame rasterizeSurfaces(const SurfaceSet& set, const Camera& camera, const RenderSettings& settings,
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
