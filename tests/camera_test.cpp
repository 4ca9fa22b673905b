/// @file camera_test.cpp
/// @brief Our cameras against OpenVDB's own (tools/RayTracer.h), ray by ray.
#include <vdb_ewa/camera.h>
#include <vdb_ewa/error.h>

#include <gtest/gtest.h>

#include <openvdb/tools/RayTracer.h>

using namespace vdb_ewa;

namespace {

openvdb::Vec3d ov(const Vec3d& v) { return {v.x, v.y, v.z}; }

/// Compare ray directions (and ortho origins) at the corners and centre of the image.
void expectSameRays(const Camera& ours, openvdb::tools::BaseCamera& theirs)
{
    const int w = ours.width(), h = ours.height();
    for (auto [i, j] : {std::pair{0, 0}, {w - 1, 0}, {0, h - 1}, {w - 1, h - 1}, {w / 2, h / 3}}) {
        const openvdb::math::Ray<double> ray = theirs.getRay(size_t(i), size_t(j));
        Vec3d origin, dir;
        ours.worldRay(i + 0.5, j + 0.5, origin, dir);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(dir[c], ray.dir()[c], 1e-9) << "pixel " << i << "," << j;
            EXPECT_NEAR(origin[c], ray(ray.t0())[c], 1e-9) << "pixel " << i << "," << j;
        }
    }
}

} // namespace

TEST(Camera, PerspectiveRotateMatchesOpenVDB)
{
    CameraSettings s;
    s.width = 64;
    s.height = 48;
    s.translate = Vec3d(1, 2, 3);
    s.rotate = Vec3d(10, -35, 20);
    s.focal = 35;
    const Camera ours(s, Vec3d(0.0));
    openvdb::tools::Film film(64, 48);
    openvdb::tools::PerspectiveCamera theirs(film, ov(*s.rotate), ov(s.translate), s.focal, s.aperture, s.near, s.far);
    expectSameRays(ours, theirs);
}

TEST(Camera, PerspectiveLookAtMatchesOpenVDB)
{
    CameraSettings s;
    s.width = 80;
    s.height = 30;
    s.translate = Vec3d(-7.381, 40.48, 237.4);
    s.lookAt = Vec3d(-7.381, 40.48, 0.4762);
    s.up = Vec3d(0.1, 1, 0.2);
    const Camera ours(s, Vec3d(0.0));
    openvdb::tools::Film film(80, 30);
    openvdb::tools::PerspectiveCamera theirs(film, openvdb::Vec3d(0.0), ov(s.translate), s.focal, s.aperture);
    theirs.lookAt(ov(*s.lookAt), ov(s.up));
    expectSameRays(ours, theirs);
}

TEST(Camera, DefaultTargetIsUsedWithoutRotateOrLookAt)
{
    CameraSettings s;
    s.width = 40;
    s.height = 40;
    s.translate = Vec3d(10, 12, 18);
    const Camera ours(s, Vec3d(1, 2, 3));
    openvdb::tools::Film film(40, 40);
    openvdb::tools::PerspectiveCamera theirs(film, openvdb::Vec3d(0.0), ov(s.translate));
    theirs.lookAt(openvdb::Vec3d(1, 2, 3));
    expectSameRays(ours, theirs);
    // The target projects to the image centre.
    const Vec2d c = ours.rasterFromCamera(ours.cameraFromWorldPoint(Vec3d(1, 2, 3)));
    EXPECT_NEAR(c.x, 20.0, 1e-9);
    EXPECT_NEAR(c.y, 20.0, 1e-9);
}

TEST(Camera, OrthographicMatchesOpenVDB)
{
    CameraSettings s;
    s.projection = Projection::Orthographic;
    s.width = 50;
    s.height = 20;
    s.translate = Vec3d(0.5, -1, 4);
    s.rotate = Vec3d(5, 15, -10);
    s.frame = 3.0;
    const Camera ours(s, Vec3d(0.0));
    openvdb::tools::Film film(50, 20);
    openvdb::tools::OrthographicCamera theirs(film, ov(*s.rotate), ov(s.translate), s.frame, s.near, s.far);
    expectSameRays(ours, theirs);
}

TEST(Camera, FieldOfViewAndFocalLengthAgreeWithOpenVDB)
{
    CameraSettings s;
    s.setFieldOfView(60.0);
    EXPECT_NEAR(s.focal, openvdb::tools::PerspectiveCamera::fieldOfViewToFocalLength(60.0, s.aperture), 1e-12);
    EXPECT_NEAR(s.fieldOfView(), 60.0, 1e-12);
}

TEST(Camera, EyeAtTheDefaultTargetLooksDownZ)
{
    // An empty or one-voxel grid at the origin, seen from the default eye (the origin): no
    // target to aim at, so vdb_render's frame without --lookat, looking down -z.
    const Camera c(CameraSettings(), Vec3d(0.0));
    EXPECT_TRUE(c.looksDownZByDefault());
    EXPECT_NEAR(c.cameraFromWorldPoint(Vec3d(0, 0, -1)).z, 1.0, 1e-12); // ahead: depth +1
    EXPECT_NEAR(c.cameraFromWorldPoint(Vec3d(1, 0, 0)).x, 1.0, 1e-12);
    EXPECT_FALSE(Camera(CameraSettings(), Vec3d(0, 0, -3)).looksDownZByDefault());
}

TEST(Camera, DefaultTargetAlongUpGetsAnotherUp)
{
    // A grid right below the default eye (fog_tommy_v5): the view runs along --up. At the
    // default target another world axis becomes the image's up; at an explicit --lookat the
    // camera stays impossible.
    const Camera below(CameraSettings(), Vec3d(0, -5, 0));
    EXPECT_TRUE(below.upReplacedByDefault());
    EXPECT_NEAR(below.cameraFromWorldPoint(Vec3d(0, -5, 0)).z, 5.0, 1e-12); // the target ahead
    EXPECT_NEAR(below.cameraFromWorldPoint(Vec3d(0, -5, 0)).x, 0.0, 1e-12);
    EXPECT_FALSE(Camera(CameraSettings(), Vec3d(0, 0, -5)).upReplacedByDefault());
    CameraSettings explicitTarget;
    explicitTarget.lookAt = Vec3d(0, -5, 0);
    EXPECT_THROW(Camera(explicitTarget, Vec3d(0.0)), ValueError);
}

TEST(Camera, ImpossibleCamerasAreRejected)
{
    auto expectRejected = [](CameraSettings s) { EXPECT_THROW(Camera(s, Vec3d(0.0)), ValueError); };
    CameraSettings s;
    s.translate = Vec3d(0, 0, 5);
    CameraSettings bad = s;
    bad.lookAt = Vec3d(0, 0, 5); // eye at the target
    expectRejected(bad);
    bad = s;
    bad.up = Vec3d(0, 0, 1); // up along the view direction
    expectRejected(bad);
    bad = s;
    bad.near = 0.0;
    expectRejected(bad);
    bad = s;
    bad.far = bad.near;
    expectRejected(bad);
    bad = s;
    bad.width = 0;
    expectRejected(bad);
    bad = s;
    bad.focal = -1;
    expectRejected(bad);
    bad = s;
    bad.width = bad.height = 65536; // 2^32 pixels: refused up front, not in bad_alloc after the render
    expectRejected(bad);
    bad.width = 16384;
    bad.height = 8192; // 2^27: the budget itself
    EXPECT_NO_THROW(Camera(bad, Vec3d(0.0)));
    bad = s;
    bad.rotate = Vec3d(0.0);
    bad.lookAt = Vec3d(1.0);
    expectRejected(bad);
    bad = s;
    bad.translate.x = std::nan("");
    expectRejected(bad);
    EXPECT_THROW(s.setFieldOfView(180.0), ValueError);
}
