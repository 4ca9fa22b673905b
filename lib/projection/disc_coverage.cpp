/// @file disc_coverage.cpp
#include "projection/disc_coverage.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vdb_ewa {
namespace detail {

bool DiscCoverage::depthOffset(double x, double y, double& dz) const
{
    x -= ox;
    y -= oy;
    const double w = W[0] * x + W[1] * y + W[2];
    if (!(w > 1e-9)) return false;
    dz = (Z[0] * x + Z[1] * y + Z[2]) / w;
    return std::isfinite(dz);
}

bool DiscCoverage::keptSide(double x, double y) const
{
    return keptSideLocal(x - ox, y - oy);
}

bool DiscCoverage::covers(double x, double y) const
{
    return coversLocal(x - ox, y - oy);
}

std::uint16_t DiscCoverage::mask(double px, double py) const
{
    if (px + 0.5 < box[0] || px - 0.5 > box[2] || py + 0.5 < box[1] || py - 0.5 > box[3]) return 0;
    const double x = px - ox, y = py - oy;
    // The pixel's square maps to a convex quadrilateral of the plane, the clipped disc is
    // convex: inside when the four corners are.
    if (coversLocal(x - 0.5, y - 0.5) && coversLocal(x + 0.5, y - 0.5) && coversLocal(x - 0.5, y + 0.5) &&
        coversLocal(x + 0.5, y + 0.5))
        return kAllSubsamples;
    // Only the subsamples inside the box can be covered.
    std::uint16_t bits = 0;
    for (int j = 0; j < kSubsamplesPerAxis; ++j) {
        const double sy = (j + 0.5) / kSubsamplesPerAxis - 0.5;
        if (py + sy < box[1] || py + sy > box[3]) continue;
        for (int i = 0; i < kSubsamplesPerAxis; ++i) {
            const double sx = (i + 0.5) / kSubsamplesPerAxis - 0.5;
            if (px + sx < box[0] || px + sx > box[2]) continue;
            if (coversLocal(x + sx, y + sy)) bits = std::uint16_t(bits | (1u << (j * kSubsamplesPerAxis + i)));
        }
    }
    return bits;
}

DiscCoverage discCoverage(const Vec3d& centre, const Vec3d& normal, double radius, const Vec3d* clipDirections,
    const double* clipDistances, int clipCount, const Camera& camera)
{
    DiscCoverage d;
    d.clipCount = std::clamp(clipCount, 0, 3);
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
    // h around the centre's raster point: h_raster = T h with T's last column (ox, oy, 1).
    const bool perspective = camera.projection() == Projection::Perspective;
    d.ox = perspective && centre.z > 1e-12 ? pp.x + f * centre.x / centre.z : pp.x + f * centre.x;
    d.oy = perspective && centre.z > 1e-12 ? pp.y + f * centre.y / centre.z : pp.y + f * centre.y;
    if (!std::isfinite(d.ox) || !std::isfinite(d.oy)) d.ox = d.oy = 0.0;
    auto local = [&](const Vec3d& row) { return Vec3d(row.x, row.y, row.x * d.ox + row.y * d.oy + row.z); };
    Vec3d V[3];
    for (int r = 0; r < 3; ++r) V[r] = local(rows[r]);
    const Vec3d W = local(wRow);
    // M = V^T V - radius^2 W W^T: h^T M h = |v|^2 - radius^2 w^2.
    auto m = [&](int i, int j) { return V[0][i] * V[0][j] + V[1][i] * V[1][j] + V[2][i] * V[2][j] - radius * radius * W[i] * W[j]; };
    d.conic[0] = m(0, 0);
    d.conic[1] = 2.0 * m(0, 1);
    d.conic[2] = m(1, 1);
    d.conic[3] = 2.0 * m(0, 2);
    d.conic[4] = 2.0 * m(1, 2);
    d.conic[5] = m(2, 2);
    for (int c = 0; c < 3; ++c) {
        d.W[c] = W[c];
        d.Z[c] = V[2][c];
    }
    // clipDirection . v - clipDistance w = (V^T clipDirection - clipDistance W) . h.
    for (int c = 0; c < d.clipCount; ++c) {
        const Vec3d& u = clipDirections[c];
        for (int j = 0; j < 3; ++j) d.clip[c][j] = u.x * V[0][j] + u.y * V[1][j] + u.z * V[2][j] - clipDistances[c] * W[j];
    }
    // The raster box of the disc's camera-space bounding box (the disc spans radius sqrt(1 - n_i^2)
    // along axis i); unbounded if part of it is not in front of the eye.
    const Vec3d extent = radius * Vec3d(std::sqrt(std::max(0.0, 1.0 - normal.x * normal.x)),
                                     std::sqrt(std::max(0.0, 1.0 - normal.y * normal.y)),
                                     std::sqrt(std::max(0.0, 1.0 - normal.z * normal.z)));
    const double inf = std::numeric_limits<double>::infinity();
    d.box[0] = d.box[1] = inf;
    d.box[2] = d.box[3] = -inf;
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
    // Where the disc's image is an ellipse, its own box is tighter (for an oblique disc by up to
    // sqrt 2 along each axis): the tangents x = const and y = const of the conic, where the
    // discriminant of the quadratic along the other axis vanishes.
    const double a = d.conic[0], b = d.conic[1], c = d.conic[2], dd = d.conic[3], e = d.conic[4], g = d.conic[5];
    const double A = b * b - 4.0 * a * c;
    if (a > 0.0 && A < 0.0) {
        auto range = [&](double B, double C, double origin, double& lo, double& hi) {
            const double disc = B * B - 4.0 * A * C;
            if (!(disc >= 0.0)) {
                lo = inf; // the conic holds no point: the disc is not seen
                hi = -inf;
                return;
            }
            const double r0 = (-B + std::sqrt(disc)) / (2.0 * A), r1 = (-B - std::sqrt(disc)) / (2.0 * A);
            const double margin = 1e-9 * (1.0 + std::abs(r0) + std::abs(r1));
            lo = std::max(lo, origin + std::min(r0, r1) - margin);
            hi = std::min(hi, origin + std::max(r0, r1) + margin);
        };
        range(2.0 * b * e - 4.0 * c * dd, e * e - 4.0 * c * g, d.ox, d.box[0], d.box[2]);
        range(2.0 * b * dd - 4.0 * a * e, dd * dd - 4.0 * a * g, d.oy, d.box[1], d.box[3]);
    }
    return d;
}

} // namespace detail
} // namespace vdb_ewa
