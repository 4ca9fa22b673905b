/// @file disc_coverage.cpp
#include "raster/disc_coverage.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vdb_ewa {
namespace detail {

void DiscCoverage::homogeneous(double x, double y, Vec3d& v, double& w) const
{
    w = W[0] * x + W[1] * y + W[2];
    v = Vec3d(V[0][0] * x + V[0][1] * y + V[0][2], V[1][0] * x + V[1][1] * y + V[1][2], V[2][0] * x + V[2][1] * y + V[2][2]);
}

bool DiscCoverage::planeOffset(double x, double y, Vec3d& offset) const
{
    Vec3d v;
    double w;
    homogeneous(x, y, v, w);
    if (!(w > 1e-9)) return false;
    offset = v / w;
    return std::isfinite(offset.z);
}

bool DiscCoverage::keptSide(const Vec3d& v, double w) const
{
    for (int c = 0; c < clipCount; ++c) {
        if (glm::dot(clipDirection[c], v) > clipDistance[c] * w) return false;
    }
    return true;
}

bool DiscCoverage::covers(double x, double y) const
{
    Vec3d v;
    double w;
    homogeneous(x, y, v, w);
    return w > 0.0 && glm::dot(v, v) <= radius2 * w * w && keptSide(v, w);
}

std::uint16_t DiscCoverage::mask(double px, double py) const
{
    if (px + 0.5 < box[0] || px - 0.5 > box[2] || py + 0.5 < box[1] || py - 0.5 > box[3]) return 0;
    // The pixel's square maps to a convex quadrilateral of the plane, the clipped disc is
    // convex: inside when the four corners are.
    if (covers(px - 0.5, py - 0.5) && covers(px + 0.5, py - 0.5) && covers(px - 0.5, py + 0.5) && covers(px + 0.5, py + 0.5))
        return kAllSubsamples;
    std::uint16_t bits = 0;
    for (int j = 0; j < kSubsamplesPerAxis; ++j)
        for (int i = 0; i < kSubsamplesPerAxis; ++i) {
            const double ox = (i + 0.5) / kSubsamplesPerAxis - 0.5, oy = (j + 0.5) / kSubsamplesPerAxis - 0.5;
            if (covers(px + ox, py + oy)) bits = std::uint16_t(bits | (1u << (j * kSubsamplesPerAxis + i)));
        }
    return bits;
}

DiscCoverage discCoverage(const Vec3d& centre, const Vec3d& normal, double radius, const Vec3d* clipDirections,
    const double* clipDistances, int clipCount, const Camera& camera)
{
    DiscCoverage d{};
    d.radius2 = radius * radius;
    d.clipCount = std::clamp(clipCount, 0, 3);
    for (int c = 0; c < d.clipCount; ++c) {
        d.clipDirection[c] = clipDirections[c];
        d.clipDistance[c] = clipDistances[c];
    }
    const double f = camera.focalPixels();
    const Vec2d pp = camera.principalPoint();
    // Rows of P: h = (x, y, 1) -> camera-plane coordinates X = (x - px) / f, Y = (y - py) / f.
    const Vec3d P0(1.0 / f, 0.0, -pp.x / f), P1(0.0, 1.0 / f, -pp.y / f), P2(0.0, 0.0, 1.0);
    const double offset = glm::dot(normal, centre);
    Vec3d rows[3], wRow;
    if (camera.projection() == Projection::Perspective) {
        // q = ray (offset / n.ray), ray = (X, Y, 1): q - centre = (offset ray - centre (n.ray)) / (n.ray),
        // signed so that w > 0 where offset / n.ray > 0 (in front of the eye).
        const double sgn = offset < 0.0 ? -1.0 : 1.0;
        const Vec3d nP = normal.x * P0 + normal.y * P1 + normal.z * P2; // n.ray = nP . h
        wRow = sgn * nP;
        const Vec3d P[3] = {P0, P1, P2};
        for (int r = 0; r < 3; ++r) rows[r] = sgn * (offset * P[r] - centre[r] * nP);
    } else {
        // q = (X, Y, (offset - nx X - ny Y) / nz); w = |nz|.
        const double a = std::abs(normal.z), sgn = normal.z < 0.0 ? -1.0 : 1.0;
        wRow = Vec3d(0.0, 0.0, a);
        rows[0] = a * P0 - Vec3d(0.0, 0.0, a * centre.x);
        rows[1] = a * P1 - Vec3d(0.0, 0.0, a * centre.y);
        rows[2] = sgn * (offset * P2 - normal.x * P0 - normal.y * P1) - Vec3d(0.0, 0.0, a * centre.z);
    }
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) d.V[r][c] = rows[r][c];
    for (int c = 0; c < 3; ++c) d.W[c] = wRow[c];
    // The raster box of the disc's camera-space bounding box (the disc spans radius sqrt(1 - n_i^2)
    // along axis i); unbounded if part of it is not in front of the eye.
    const Vec3d extent = radius * Vec3d(std::sqrt(std::max(0.0, 1.0 - normal.x * normal.x)),
                                     std::sqrt(std::max(0.0, 1.0 - normal.y * normal.y)),
                                     std::sqrt(std::max(0.0, 1.0 - normal.z * normal.z)));
    const double inf = std::numeric_limits<double>::infinity();
    d.box[0] = d.box[1] = inf;
    d.box[2] = d.box[3] = -inf;
    const bool perspective = camera.projection() == Projection::Perspective;
    for (int corner = 0; corner < 8; ++corner) {
        const Vec3d p = centre + Vec3d((corner & 1) ? extent.x : -extent.x, (corner & 2) ? extent.y : -extent.y,
                                     (corner & 4) ? extent.z : -extent.z);
        if (perspective && !(p.z > 1e-12)) {
            d.box[0] = d.box[1] = -inf;
            d.box[2] = d.box[3] = inf;
            break;
        }
        const double x = perspective ? pp.x + f * p.x / p.z : pp.x + f * p.x;
        const double y = perspective ? pp.y + f * p.y / p.z : pp.y + f * p.y;
        d.box[0] = std::min(d.box[0], x);
        d.box[1] = std::min(d.box[1], y);
        d.box[2] = std::max(d.box[2], x);
        d.box[3] = std::max(d.box[3], y);
    }
    return d;
}

} // namespace detail
} // namespace vdb_ewa
