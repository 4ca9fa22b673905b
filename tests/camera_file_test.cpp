/// @file camera_file_test.cpp
/// @brief Cameras from files (include/vdb_ewa/camera_file.h): the exact record round-trips,
///        and a worldToCamera matrix gives back the camera that made it.
#include "fixtures.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace vdb_ewa;

namespace {

void expectSameSettings(const CameraSettings& a, const CameraSettings& b)
{
    EXPECT_EQ(a.projection, b.projection);
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_EQ(a.translate, b.translate);
    EXPECT_EQ(a.rotate, b.rotate);
    EXPECT_EQ(a.lookAt, b.lookAt);
    EXPECT_EQ(a.up, b.up);
    for (const auto& [x, y] : {std::pair{a.focal, b.focal}, {a.aperture, b.aperture}, {a.frame, b.frame}, {a.near, b.near}, {a.far, b.far}}) {
        EXPECT_EQ(x, y);
    }
}

/// OpenEXR's worldToCamera of @a camera (row vectors; x right, y up, z forward), as
/// exr_output.cpp writes it, in double.
void worldToCamera(const Camera& camera, double m[4][4])
{
    const Mat3d& r = camera.cameraFromWorld(); // rows: right, down, forward
    const double flip[3] = {1.0, -1.0, 1.0};
    for (int row = 0; row < 3; ++row) {
        const Vec3d axis = flip[row] * Vec3d(r[0][row], r[1][row], r[2][row]);
        for (int k = 0; k < 3; ++k) m[k][row] = axis[k];
        m[3][row] = -glm::dot(axis, camera.eye());
    }
    m[0][3] = m[1][3] = m[2][3] = 0.0;
    m[3][3] = 1.0;
}

} // namespace

TEST(CameraFile, RecordRoundTripsExactly)
{
    CameraSettings look;
    look.width = 640;
    look.height = 360;
    look.translate = Vec3d(0.1, 1.0 / 3.0, -7e-8);
    look.lookAt = Vec3d(1e-300, 2.5, std::nextafter(3.0, 4.0));
    look.up = Vec3d(0.1, 0.9, 0.0);
    look.setFieldOfView(33.3);
    CameraSettings ortho;
    ortho.projection = Projection::Orthographic;
    ortho.rotate = Vec3d(10.0, -35.0, 1.0 / 7.0);
    ortho.frame = 2.0 / 3.0;
    ortho.near = 0.25;
    ortho.far = 1e9;
    for (const CameraSettings& s : {look, ortho}) expectSameSettings(cameraFromRecord(cameraRecord(s)), s);
    CameraSettings none;
    EXPECT_THROW(cameraRecord(none), ValueError) << "a camera that leaves its target to the grid";
    for (const char* bad : {"", "projection=perspective", "projection=fisheye;res=1x1;translate=0,0,0;rotate=0,0,0;focal=1;aperture=1;frame=1;near=1;far=2",
             "projection=perspective;res=1x1;translate=0,0;rotate=0,0,0;focal=1;aperture=1;frame=1;near=1;far=2",
             "projection=perspective;res=1x1;translate=0,0,0;rotate=0,0,0;focal=-1;aperture=1;frame=1;near=1;far=2"}) {
        EXPECT_THROW(cameraFromRecord(bad), ValueError) << bad;
    }
}

TEST(CameraFile, WorldToCameraGivesBackTheCameraThatMadeIt)
{
    // Rotations about every axis, gimbal lock (y = +-90) and a look-at camera: the matrix's
    // camera has the same eye, axes and field of view to 1e-12.
    CameraSettings base;
    base.width = 320;
    base.height = 200;
    base.translate = Vec3d(3.0, -2.0, 40.0);
    base.setFieldOfView(28.0);
    std::vector<CameraSettings> cameras;
    for (const Vec3d r : {Vec3d(10.0, -35.0, 20.0), Vec3d(-170.0, 60.0, 95.0), Vec3d(0.0, 90.0, 30.0), Vec3d(20.0, -90.0, 0.0)}) {
        CameraSettings s = base;
        s.rotate = r;
        cameras.push_back(s);
    }
    CameraSettings look = base;
    look.lookAt = Vec3d(0.5, 1.0, -3.0);
    cameras.push_back(look);
    CameraSettings ortho = base;
    ortho.projection = Projection::Orthographic;
    ortho.frame = 12.5;
    ortho.rotate = Vec3d(5.0, 5.0, 5.0);
    cameras.push_back(ortho);
    for (const CameraSettings& s : cameras) {
        const Camera original(s, Vec3d(0.0));
        double m[4][4];
        worldToCamera(original, m);
        const double window = double(s.width) / original.focalPixels();
        const Camera read(cameraFromWorldToCamera(m, s.projection, window, s.width, s.height), Vec3d(0.0));
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(read.eye()[k], original.eye()[k], 1e-12 * 40.0);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) EXPECT_NEAR(read.cameraFromWorld()[i][j], original.cameraFromWorld()[i][j], 1e-12);
        EXPECT_NEAR(read.focalPixels(), original.focalPixels(), 1e-9 * original.focalPixels());
        EXPECT_EQ(read.projection(), s.projection);
    }
    double zero[4][4] = {};
    EXPECT_THROW(cameraFromWorldToCamera(zero, Projection::Perspective, 1.0, 10, 10), ValueError);
}
