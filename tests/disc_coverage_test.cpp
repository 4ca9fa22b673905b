/// @file disc_coverage_test.cpp
/// @brief A surface kernel's disc seen through the camera (projection/disc_coverage.h) against
///        the ray-plane intersection it replaces.
#include "projection/projection.h"

#include <gtest/gtest.h>

#include <random>

using namespace vdb_ewa;
using namespace vdb_ewa::detail;

namespace {

struct Disc
{
    Vec3d centre, normal;
    double radius;
    Vec3d clipDirection[3];
    double clipDistance[3];
    int clips;
};

/// Whether the ray through raster (x, y) meets @a d: the plane point by division, then the
/// disc and its clips. -1 where the point lies within 1e-9 of an edge (either answer is right).
int bruteForce(const Disc& d, const Camera& camera, double x, double y)
{
    const double f = camera.focalPixels();
    const Vec2d pp = camera.principalPoint();
    const double X = (x - pp.x) / f, Y = (y - pp.y) / f;
    Vec3d q;
    const double offset = glm::dot(d.normal, d.centre);
    if (camera.projection() == Projection::Perspective) {
        const Vec3d ray(X, Y, 1.0);
        const double along = offset / glm::dot(d.normal, ray);
        if (!(along > 0.0)) return 0;
        q = ray * along;
    } else {
        q = Vec3d(X, Y, (offset - d.normal.x * X - d.normal.y * Y) / d.normal.z);
    }
    const Vec3d v = q - d.centre;
    const double edge = glm::length(v) - d.radius;
    if (std::abs(edge) < 1e-9) return -1;
    bool inside = edge < 0.0;
    for (int c = 0; c < d.clips; ++c) {
        const double side = glm::dot(d.clipDirection[c], v) - d.clipDistance[c];
        if (std::abs(side) < 1e-9) return -1;
        inside = inside && side <= 0.0;
    }
    return inside ? 1 : 0;
}

Disc randomDisc(std::mt19937& rng)
{
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Disc d;
    d.centre = Vec3d(u(rng), u(rng), 4.0 + 3.0 * u(rng));
    // Facing the eye, up to 85 degrees off the view direction.
    do {
        d.normal = glm::normalize(Vec3d(u(rng), u(rng), u(rng)));
    } while (!(glm::dot(d.normal, glm::normalize(d.centre)) < -0.09));
    d.radius = 0.2 + 0.4 * (u(rng) + 1.0);
    d.clips = int(rng() % 4);
    for (int c = 0; c < d.clips; ++c) {
        const Vec3d a(u(rng), u(rng), u(rng));
        d.clipDirection[c] = glm::normalize(a - glm::dot(a, d.normal) * d.normal);
        d.clipDistance[c] = 0.5 * d.radius * (u(rng) + 1.0);
    }
    return d;
}

Camera camera(Projection projection)
{
    CameraSettings s;
    s.width = 320;
    s.height = 240;
    s.projection = projection;
    s.frame = 4.0;
    s.translate = Vec3d(0.0, 0.0, 5.0);
    s.lookAt = Vec3d(0.0);
    return Camera(s, Vec3d(0.0));
}

} // namespace

// covers() is the ray-plane test without a division: a plane seen through a perspective or
// orthographic camera is a projective map of the raster. Every raster point of 200 random
// clipped discs agrees with the division, and the box holds every covered point.
TEST(DiscCoverage, CoversWhatTheRayPlaneIntersectionCovers)
{
    std::mt19937 rng(16);
    for (const Projection projection : {Projection::Perspective, Projection::Orthographic}) {
        const Camera cam = camera(projection);
        int compared = 0, covered = 0;
        for (int i = 0; i < 200; ++i) {
            const Disc d = randomDisc(rng);
            const DiscCoverage dc = discCoverage(d.centre, d.normal, d.radius, d.clipDirection, d.clipDistance, d.clips, cam);
            for (double y = 0.25; y < 240.0; y += 1.5)
                for (double x = 0.25; x < 320.0; x += 1.5) {
                    const int expected = bruteForce(d, cam, x, y);
                    if (expected < 0) continue;
                    const bool got = dc.covers(x, y);
                    ASSERT_EQ(got, expected == 1) << "disc " << i << " at " << x << ", " << y;
                    ++compared;
                    if (got) {
                        ++covered;
                        EXPECT_TRUE(x >= dc.box[0] && x <= dc.box[2] && y >= dc.box[1] && y <= dc.box[3]);
                    }
                }
        }
        EXPECT_GT(covered, 10000) << "the discs are seen";
        EXPECT_GT(compared, 1000000);
    }
}

// mask() sets the bits of the 4x4 subsamples whose rays meet the disc: its shortcuts (the box,
// four corners inside) agree with testing every subsample.
TEST(DiscCoverage, MaskHoldsTheCoveredSubsamples)
{
    std::mt19937 rng(7);
    const Camera cam = camera(Projection::Perspective);
    int partial = 0, full = 0;
    for (int i = 0; i < 200; ++i) {
        const Disc d = randomDisc(rng);
        const DiscCoverage dc = discCoverage(d.centre, d.normal, d.radius, d.clipDirection, d.clipDistance, d.clips, cam);
        for (int py = 0; py < 240; py += 3)
            for (int px = 0; px < 320; px += 3) {
                const double cx = px + 0.5, cy = py + 0.5;
                std::uint16_t expected = 0;
                for (int j = 0; j < kSubsamplesPerAxis; ++j)
                    for (int k = 0; k < kSubsamplesPerAxis; ++k) {
                        const double ox = (k + 0.5) / kSubsamplesPerAxis - 0.5, oy = (j + 0.5) / kSubsamplesPerAxis - 0.5;
                        if (dc.covers(cx + ox, cy + oy)) expected = std::uint16_t(expected | (1u << (j * kSubsamplesPerAxis + k)));
                    }
                const std::uint16_t got = dc.mask(cx, cy);
                ASSERT_EQ(got, expected) << "disc " << i << " pixel " << px << ", " << py;
                partial += got != 0 && got != kAllSubsamples;
                full += got == kAllSubsamples;
            }
    }
    EXPECT_GT(partial, 1000);
    EXPECT_GT(full, 1000);
}

// The box is the disc's own where its image is an ellipse: each side touches it (a covered
// point within 0.02 pixels inside each side), not the image of the disc's 3D bounding box,
// which is up to sqrt 2 wider along an axis for an oblique disc (the pixels visited for
// coverage follow the box).
TEST(DiscCoverage, BoxTouchesTheDiscsImage)
{
    std::mt19937 rng(11);
    for (const Projection projection : {Projection::Perspective, Projection::Orthographic}) {
        const Camera cam = camera(projection);
        int checked = 0;
        for (int i = 0; i < 100; ++i) {
            Disc d = randomDisc(rng);
            d.clips = 0; // clips cut the disc inside its box
            const DiscCoverage dc = discCoverage(d.centre, d.normal, d.radius, d.clipDirection, d.clipDistance, d.clips, cam);
            if (!(dc.box[0] > 0.0 && dc.box[2] < 320.0 && dc.box[1] > 0.0 && dc.box[3] < 240.0)) continue; // in view
            const double inset = 0.02, step = 0.002;
            bool left = false, right = false, top = false, bottom = false;
            for (double y = dc.box[1]; y <= dc.box[3]; y += step) {
                left = left || dc.covers(dc.box[0] + inset, y);
                right = right || dc.covers(dc.box[2] - inset, y);
            }
            for (double x = dc.box[0]; x <= dc.box[2]; x += step) {
                top = top || dc.covers(x, dc.box[1] + inset);
                bottom = bottom || dc.covers(x, dc.box[3] - inset);
            }
            EXPECT_TRUE(left && right && top && bottom) << "disc " << i << ": box " << dc.box[0] << ", " << dc.box[1] << " - "
                                                        << dc.box[2] << ", " << dc.box[3];
            ++checked;
        }
        EXPECT_GT(checked, 50);
    }
}
