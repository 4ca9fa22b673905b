/// @file light_on_demand.cpp
#include "raster/light_on_demand.h"

#include "raster/tile_bins.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace vdb_ewa {
namespace detail {

std::uint64_t lightWindow(const SplatSet& window, const Camera& camera, std::vector<LightMap>& lights, Progress* progress,
    const TilesOpaque& opaque)
{
    if (lights.empty() || window.splats.empty()) return 0;
    const Mat3d worldFromCamera = glm::transpose(camera.cameraFromWorld());
    const Vec2d centre = camera.principalPoint();
    const double f = camera.focalPixels();
    const bool perspective = camera.projection() == Projection::Perspective;
    // The world point at raster (x, y) and camera depth z (t2).
    const auto worldAt = [&](double x, double y, double z) {
        const Vec2d plane = (Vec2d(x, y) - centre) / f;
        const Vec3d t = perspective ? Vec3d(plane.x * z, plane.y * z, z) : Vec3d(plane.x, plane.y, z);
        return camera.eye() + worldFromCamera * t;
    };
    for (LightMap& light : lights) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, window.splats.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t s = r.begin(); s < r.end(); ++s) {
                const Splat& sp = window.splats[s];
                if (opaque && opaque(sp.x0 / kTileSize, sp.y0 / kTileSize, sp.x1 / kTileSize, sp.y1 / kTileSize)) continue;
                // Pixel edges around the box (lookups are at pixel centres), the slabs' planes.
                const double x[2] = {double(sp.x0), double(sp.x1) + 1.0}, y[2] = {double(sp.y0), double(sp.y1) + 1.0};
                double z[2] = {window.slabs.start(sp.firstSlab), window.slabs.start(sp.firstSlab + std::int64_t(sp.slabCount))};
                if (perspective) {
                    // A perspective camera's slabs are in distance s along the pixel's ray: there
                    // t2 = s cos(theta), between s0 cos(theta) at the box's widest corner and s1.
                    double widest = 1.0;
                    for (int c = 0; c < 4; ++c) {
                        const Vec2d plane = (Vec2d(x[c & 1], y[c >> 1]) - centre) / f;
                        widest = std::min(widest, 1.0 / std::sqrt(1.0 + glm::dot(plane, plane)));
                    }
                    z[0] *= widest;
                }
                Vec3d lo(1e300), hi(-1e300);
                for (int c = 0; c < 8; ++c) {
                    const Vec3d q = light.coordinates(worldAt(x[c & 1], y[(c >> 1) & 1], z[c >> 2]));
                    lo = glm::min(lo, q);
                    hi = glm::max(hi, q);
                }
                // Half a ray's spacing more: lookups in float may round across a ray.
                light.require(lo - Vec3d(0.5), hi + Vec3d(0.5));
            }
        });
    }
    std::uint64_t tiles = 0;
    for (LightMap& light : lights) tiles += light.marchRequired(progress);
    return tiles;
}

} // namespace detail
} // namespace vdb_ewa
