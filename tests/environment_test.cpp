/// @file environment_test.cpp
/// @brief The latitude-longitude environment as directional lights: its convention, its energy,
///        and its shadowed fill against the unshadowed --ambient.
#include "fixtures.h"

#include <vdb_ewa/environment.h>
#include <vdb_ewa/error.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

constexpr double kPi = 3.14159265358979323846;

void expectDirection(const Vec3d& got, const Vec3d& expected)
{
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(got[a], expected[a], 1e-12) << a;
}

/// A @a width x width/2 environment whose pixel radiance is @a radiance(direction).
template <typename F>
Image environment(int width, F radiance)
{
    Image img(width, width / 2);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const Vec3d rgb = radiance(latLongDirection((x + 0.5) / img.width, (y + 0.5) / img.height));
            float* p = img.pixel(x, y);
            p[0] = float(rgb.x);
            p[1] = float(rgb.y);
            p[2] = float(rgb.z);
            p[3] = 1.0f;
        }
    return img;
}

Vec3d colourSum(const std::vector<Light>& lights)
{
    Vec3d sum(0.0);
    for (const Light& l : lights) sum += l.color;
    return sum;
}

} // namespace

TEST(Environment, LatLongDirectionsFollowOpenExrAndUsd)
{
    // OpenEXR's latitude-longitude map (and USD's DomeLight): "latitude 0, longitude 0 points
    // into positive z direction; and latitude 0, longitude pi/2 points into positive x
    // direction"; the first pixel has latitude +pi/2 and longitude +pi.
    expectDirection(latLongDirection(0.5, 0.5), Vec3d(0, 0, 1));
    expectDirection(latLongDirection(0.25, 0.5), Vec3d(1, 0, 0));
    expectDirection(latLongDirection(0.75, 0.5), Vec3d(-1, 0, 0));
    expectDirection(latLongDirection(0.3, 0.0), Vec3d(0, 1, 0)); // the top row is +Y
    expectDirection(latLongDirection(0.3, 1.0), Vec3d(0, -1, 0));
    expectDirection(latLongDirection(0.0, 0.5), Vec3d(0, 0, -1));
}

TEST(Environment, LightsKeepTheEnvironmentsLight)
{
    // L = (1 + cos theta, 0.5, 0): (1 / 4 pi) int L d omega = (1, 0.5, 0), whatever the count;
    // the sky's half holds 3/4 of the red.
    const Image sky = environment(256, [](const Vec3d& d) { return Vec3d(1.0 + d.y, 0.5, 0.0); });
    for (const int count : {1, 6, 16, 64}) {
        const std::vector<Light> lights = environmentLights(sky, count);
        ASSERT_EQ(lights.size(), std::size_t(count));
        const Vec3d sum = colourSum(lights);
        EXPECT_NEAR(sum.x, 1.0, 1e-3) << count;
        EXPECT_NEAR(sum.y, 0.5, 1e-3) << count;
        EXPECT_EQ(sum.z, 0.0) << count;
        double up = 0.0;
        for (const Light& l : lights) {
            EXPECT_NEAR(glm::length(l.direction), 1.0, 1e-9);
            if (l.direction.y > 0.0) up += l.color.x;
        }
        if (count >= 16) {
            EXPECT_NEAR(up, 0.75, 0.05) << count;
        }
    }
    EXPECT_NEAR(colourSum(environmentLights(sky, 16, 2.5)).x, 2.5, 3e-3) << "--environment-intensity";
}

TEST(Environment, OneBrightPixelIsOneLightFromItsDirection)
{
    // A sun of radiance S in one pixel of solid angle w: one light towards it, colour S w / 4 pi.
    Image sky(64, 32);
    const int x = 40, y = 10;
    sky.pixel(x, y)[0] = sky.pixel(x, y)[1] = sky.pixel(x, y)[2] = 1000.0f;
    const double u = (x + 0.5) / 64.0, v = (y + 0.5) / 32.0;
    const double omega = std::sin(kPi * v) * (kPi / 32.0) * (2.0 * kPi / 64.0);
    const std::vector<Light> lights = environmentLights(sky, 16);
    ASSERT_EQ(lights.size(), 1u);
    expectDirection(lights[0].direction, latLongDirection(u, v));
    EXPECT_NEAR(lights[0].color.x, 1000.0 * omega / (4.0 * kPi), 1e-9);
}

TEST(Environment, FillsLikeTheAmbientLightAndIsShadowed)
{
    // A uniform environment of radiance A is --ambient A where nothing shadows (a thin slab:
    // the lights' shadows within 5 %), and less where the slab shadows itself (dense).
    const Vec3d a(0.4, 0.6, 0.9);
    const Image sky = environment(128, [&](const Vec3d&) { return a; });
    const CameraSettings camera = orthoDownZ(-0.05, -0.05, 10.0, 1.0, 8);
    for (const float rho : {0.005f, 2.0f}) {
        const auto slab = makeBoxGrid(openvdb::Coord(-20, -20, 0), openvdb::Coord(19, 19, 11), rho, 0.1);
        RenderSettings ambient;
        ambient.lights.clear();
        ambient.ambient = a;
        ambient.cutoff = 0.0;
        RenderSettings filled = ambient;
        filled.ambient = Vec3d(0.0);
        filled.lights = environmentLights(sky, 32);
        const Image byAmbient = renderGrid(slab, camera, ambient), byEnvironment = renderGrid(slab, camera, filled);
        for (int j = 0; j < 8; ++j)
            for (int i = 0; i < 8; ++i)
                for (int c = 0; c < 3; ++c) {
                    const double ratio = double(byEnvironment.pixel(i, j)[c]) / double(byAmbient.pixel(i, j)[c]);
                    if (rho < 1.0f) {
                        EXPECT_GT(ratio, 0.95) << i << "," << j << " c " << c;
                        EXPECT_LE(ratio, 1.0 + 1e-4) << i << "," << j << " c " << c;
                    } else {
                        EXPECT_LT(ratio, 0.8) << "a dense slab shadows its fill: " << i << "," << j << " c " << c;
                    }
                }
    }
}

TEST(Environment, RefusesWhatItCannotUse)
{
    const Image sky = environment(32, [](const Vec3d&) { return Vec3d(1.0); });
    EXPECT_THROW(environmentLights(Image(), 16), ValueError);
    EXPECT_THROW(environmentLights(sky, 0), ValueError);
    EXPECT_THROW(environmentLights(sky, int(kMaxLights) + 1), ValueError);
    EXPECT_THROW(environmentLights(sky, 16, -1.0), ValueError);
    EXPECT_THROW(readLatLongImage("/nonexistent/sky.exr"), IoError);
}
