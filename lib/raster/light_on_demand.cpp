/// @file light_on_demand.cpp
#include "raster/light_on_demand.h"

#include <algorithm>
#include <cmath>

namespace vdb_ewa {
namespace detail {

void lookupBox(const Camera& camera, const LightMap& map, double x0, double y0, double x1, double y1, double z0, double z1, Vec3d& lo, Vec3d& hi)
{
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
    // The rectangle's corners (where the lookups' rays are traced), the slabs' planes.
    const double x[2] = {x0, x1}, y[2] = {y0, y1};
    double z[2] = {z0, z1};
    if (perspective) {
        // A perspective camera's slabs are in distance s along the pixel's ray: there
        // t2 = s cos(theta), between s0 cos(theta) at the rectangle's widest corner and s1
        // cos(theta) at its point nearest the image centre.
        const auto cosAt = [&](double px, double py) {
            const Vec2d plane = (Vec2d(px, py) - centre) / f;
            return 1.0 / std::sqrt(1.0 + glm::dot(plane, plane));
        };
        double widest = 1.0;
        for (int c = 0; c < 4; ++c) widest = std::min(widest, cosAt(x[c & 1], y[c >> 1]));
        z[0] *= widest;
        z[1] *= cosAt(std::clamp(centre.x, x[0], x[1]), std::clamp(centre.y, y[0], y[1]));
    }
    lo = Vec3d(1e300);
    hi = Vec3d(-1e300);
    for (int c = 0; c < 8; ++c) {
        const Vec3d q = map.coordinates(worldAt(x[c & 1], y[(c >> 1) & 1], z[c >> 2]));
        lo = glm::min(lo, q);
        hi = glm::max(hi, q);
    }
    // A hundredth of a ray's spacing more: the lookups form their points in double from the
    // same camera, on layers whose ends (floats) the two rasteriser backends may round an ulp
    // apart.
    lo -= Vec3d(0.01);
    hi += Vec3d(0.01);
}

} // namespace detail
} // namespace vdb_ewa
