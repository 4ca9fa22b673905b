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

/// Summed weights at or above this are full coverage: the kernels' partition of unity ripples
/// by a few per cent between kernel centres, and an opaque surface must not let 2 % of the
/// background through. At silhouettes the alpha = 0.5 contour moves by about 0.1 pixel.
constexpr double kFullCoverage = 0.9;

/// A projected, shaded surface kernel.
struct SurfaceSplat
{
    float cx, cy;          ///< centre, raster
    float qa, qb, qc;      ///< conic, 1/pixels^2
    float cutoff;          ///< evaluate where d^T Q d < cutoff
    float weight;          ///< area x footprint peak
    float colour[3];       ///< shaded colour
    Vec3d centre;          ///< camera-space centre
    Vec3d planeNormal;     ///< camera-space unit normal of the tangent plane
    double planeOffset;    ///< n . t_centre
    double depth;          ///< camera depth of the centre
    double depthRange;     ///< the kernel's disc radius (3 sigma); plane depths are clamped to depth +- it
    int x0, y0, x1, y1;
};

/// A (splat, tile pixel) pair inside the splat's cut-off: its conic distance and plane depth.
struct Pair
{
    std::uint32_t splat;
    int pixel;
    double r, z;
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
            if (!pixelBox(fp, camera.width(), camera.height(), s.x0, s.y0, s.x1, s.y1)) continue;
            setFootprint(s, fp, params.cutoffRadius);
            s.weight = float(k.area * fp.peak);
            const Vec3d rayDir = perspective ? glm::normalize(k.pWorld - camera.eye()) : forward;
            const Vec3d c = k.albedo * shade(settings.surface.shader, k.normal, rayDir, k.pWorld, set);
            for (int ch = 0; ch < 3; ++ch) s.colour[ch] = float(c[ch]);
            s.centre = t;
            s.planeNormal = normal;
            s.planeOffset = glm::dot(normal, t);
            s.depth = t.z;
            s.depthRange = 3.0 * set.sigma;
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
    double voxelLength, const PassRequest& passes, SurfaceStats& stats, Progress* progress, const MemoryBudget* budget)
{
    const int width = camera.width(), height = camera.height();
    Frame frame = blankFrame(width, height, passes);

    const std::vector<SurfaceSplat> splats = projectSurfaceSplats(set, camera, settings);
    stats.splats = splats.size();
    stats.culled = set.kernels.size() - splats.size();
    const TileBins bins = binSplats(splats, width, height, budget);
    stats.splatTilePairs = bins.indices.size();
    const double tolerance = settings.surface.tolerance * voxelLength;
    const bool perspective = camera.projection() == Projection::Perspective;
    const double f = camera.focalPixels();
    const Vec2d principal = camera.principalPoint();

    const int tiles = bins.tilesX * bins.tilesY;
    // Where the ray through pixel centre (px, py) meets splat s's tangent plane (camera space).
    auto planePoint = [&](const SurfaceSplat& s, double px, double py, Vec3d& q) {
        const double x = (px - principal.x) / f, y = (py - principal.y) / f;
        if (perspective) {
            const Vec3d ray(x, y, 1.0);
            const double denom = glm::dot(s.planeNormal, ray);
            if (!(std::abs(denom) > 1e-9)) return false;
            q = ray * (s.planeOffset / denom);
        } else {
            if (!(std::abs(s.planeNormal.z) > 1e-9)) return false;
            q = Vec3d(x, y, (s.planeOffset - s.planeNormal.x * x - s.planeNormal.y * y) / s.planeNormal.z);
        }
        return std::isfinite(q.z);
    };
    setUnits(progress, std::uint64_t(tiles));
    tbb::parallel_for(tbb::blocked_range<int>(0, tiles, 1), [&](const tbb::blocked_range<int>& range) {
        std::vector<std::uint32_t> order;
        std::vector<Pair> pairs;
        for (int t = range.begin(); t < range.end(); ++t) {
            const int x0 = (t % bins.tilesX) * kTileSize, y0 = (t / bins.tilesX) * kTileSize;
            const int w = std::min(kTileSize, width - x0), h = std::min(kTileSize, height - y0);
            order.assign(bins.indices.begin() + std::ptrdiff_t(bins.offsets[t]),
                bins.indices.begin() + std::ptrdiff_t(bins.offsets[t + 1]));
            // Pass 1: every (pixel, splat) pair inside a footprint's cut-off, with its plane depth,
            // and the front surface per pixel: the nearest depth at which its ray meets a kernel's
            // disc (3 sigma), else (silhouettes) the nearest filtered tail.
            double zDisc[kTilePixels], zTail[kTilePixels];
            std::fill(std::begin(zDisc), std::end(zDisc), std::numeric_limits<double>::infinity());
            std::fill(std::begin(zTail), std::end(zTail), std::numeric_limits<double>::infinity());
            pairs.clear();
            for (std::uint32_t index : order) {
                const SurfaceSplat& s = splats[index];
                const int lx0 = std::max(s.x0 - x0, 0), lx1 = std::min(s.x1 - x0, w - 1);
                const int ly0 = std::max(s.y0 - y0, 0), ly1 = std::min(s.y1 - y0, h - 1);
                for (int ly = ly0; ly <= ly1; ++ly)
                    for (int lx = lx0; lx <= lx1; ++lx) {
                        const double px = x0 + lx + 0.5, py = y0 + ly + 0.5;
                        const double dx = px - s.cx, dy = py - s.cy;
                        const double r = s.qa * dx * dx + 2.0 * s.qb * dx * dy + s.qc * dy * dy;
                        if (!(r < s.cutoff)) continue;
                        Vec3d q;
                        const bool hit = planePoint(s, px, py, q);
                        const double z = hit ? std::clamp(q.z, s.depth - s.depthRange, s.depth + s.depthRange) : s.depth;
                        const int p = ly * kTileSize + lx;
                        if (hit && glm::length(q - s.centre) <= s.depthRange) zDisc[p] = std::min(zDisc[p], z);
                        zTail[p] = std::min(zTail[p], z);
                        pairs.push_back({index, p, r, z});
                    }
            }
            // Pass 2: accumulate the pairs within the tolerance of that surface (Sec. 7.2).
            double zSum[kTilePixels], weight[kTilePixels], colour[kTilePixels][3];
            std::fill(std::begin(zSum), std::end(zSum), 0.0);
            std::fill(std::begin(weight), std::end(weight), 0.0);
            std::fill(&colour[0][0], &colour[0][0] + 3 * kTilePixels, 0.0);
            for (const Pair& pair : pairs) {
                const int p = pair.pixel;
                const double front = std::isinf(zDisc[p]) ? zTail[p] : zDisc[p];
                if (pair.z > front + tolerance) continue; // hidden behind the front surface
                const SurfaceSplat& s = splats[pair.splat];
                const double wt = s.weight * std::exp(-0.5 * pair.r);
                weight[p] += wt;
                zSum[p] += wt * pair.z;
                for (int c = 0; c < 3; ++c) colour[p][c] += wt * s.colour[c];
            }
            for (int ly = 0; ly < h; ++ly)
                for (int lx = 0; lx < w; ++lx) {
                    const int p = ly * kTileSize + lx;
                    const std::size_t i = std::size_t(y0 + ly) * std::size_t(width) + std::size_t(x0 + lx);
                    const double alpha = std::min(1.0, weight[p] / kFullCoverage);
                    float* px = frame.beauty.pixel(x0 + lx, y0 + ly);
                    for (int c = 0; c < 3; ++c) px[c] = weight[p] > 0.0 ? float(colour[p][c] / weight[p] * alpha) : 0.0f;
                    px[3] = float(alpha);
                    if (passes.depth && alpha >= 0.5) frame.depth[i] = float(zSum[p] / weight[p]);
                    if (passes.transmittance) std::fill_n(&frame.transmittance[3 * i], 3, float(1.0 - alpha));
                }
            advance(progress);
        }
    });
    return frame;
}

} // namespace detail
} // namespace vdb_ewa
