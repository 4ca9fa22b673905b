/// @file point_light_test.cpp
/// @brief Point and spot lights against closed forms: the light map's and the shadow ray's
///        optical depth through a uniform box (from inside it and from outside), the inverse
///        square, the spot's cone and blend; the splatter against the reference with a light
///        inside a cloud; the streamed frame equal to the whole frame.
#include "fixtures.h"

#include "shading/shading.h"
#include "source/source.h"

#include <vdb_ewa/error.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

/// A white scatterer lit by point lights only (no directional light, no gain, no cutoff).
RenderSettings pointLit(double sigma, const std::vector<PointLight>& lights)
{
    RenderSettings s;
    s.medium.absorb = Vec3d(0.0);
    s.medium.scatter = Vec3d(sigma);
    s.lights.clear();
    s.pointLights = lights;
    s.cutoff = 0.0;
    s.shadow.step = 0.25;
    s.step = 0.25;
    return s;
}

PointLight pointAt(const Vec3d& p, double intensity)
{
    PointLight l;
    l.position = p;
    l.color = Vec3d(intensity);
    return l;
}

/// The trilinear field of a box of voxels [lo, hi] of value rho along an index axis: rho on
/// [lo, hi], ramping to 0 over one voxel outside. Its integral from below the box to x.
double boxIntegral(double x, double lo, double rho)
{
    if (x <= lo - 1.0) return 0.0;
    if (x <= lo) return 0.5 * rho * (x - lo + 1.0) * (x - lo + 1.0);
    return 0.5 * rho + rho * (x - lo);
}

double sum(const Image& img, int c)
{
    double s = 0.0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) s += img.pixel(x, y)[c];
    return s;
}

} // namespace

TEST(PointLight, TheMapAndTheShadowRayIntegrateAUniformBoxExactly)
{
    // A box of density 0.5, voxels of 0.1: from a light at its centre, the optical depth to a
    // point r voxel lengths away is 0.5 r; from a light outside on the x axis, the box's
    // ramp (half a voxel) plus 0.5 (x - lo) along it.
    const double h = 0.1, rho = 0.5;
    const GridSource source = gridSourceFromOpenVDB(makeBoxGrid(openvdb::Coord(-12), openvdb::Coord(12), float(rho), h));
    const GridSource::Impl& g = source.impl();
    RenderSettings settings = pointLit(1.0, {});
    settings.shadow.step = 0.25;
    settings.shadow.resolution = 0.5;
    std::mt19937 random(7);
    std::uniform_real_distribution<double> inside(-10.0, 10.0);
    openvdb::FloatGrid::ConstAccessor accessor = g.field->getConstAccessor();
    const Vec3d boxMin(-13.0), boxMax(13.0);
    {
        const PointLight light = pointAt(Vec3d(0.03, -0.02, 0.01), 1.0);
        const detail::PointLightMap map(g, settings, light, 1e8);
        EXPECT_EQ(map.shadowStep(), 0.25);
        double worst = 0.0, worstRay = 0.0;
        for (int n = 0; n < 200; ++n) {
            const Vec3d pIndex(inside(random), inside(random), inside(random));
            const Vec3d p = g.indexToWorld(pIndex);
            const double exact = rho * glm::length(p - light.position) / h;
            worst = std::max(worst, std::abs(double(map.depth(p)) - exact));
            worstRay = std::max(worstRay, std::abs(detail::pointShadowDepth(g, accessor, pIndex, light.position, 0.25, 0.0, boxMin, boxMax) - exact));
        }
        EXPECT_LT(worst, 0.01) << "the map: linear along its rays, exact across a uniform field";
        EXPECT_LT(worstRay, 1e-6) << "the shadow ray's midpoints integrate a constant exactly";
    }
    {
        // From outside: the light 40 voxels beyond the box's -x face, on the axis.
        const PointLight light = pointAt(Vec3d(-52.0 * h, 0.0, 0.0), 1.0);
        const detail::PointLightMap map(g, settings, light, 1e8);
        for (const double x : {-11.5, -6.0, 0.0, 7.25, 11.0}) {
            const Vec3d pIndex(x, 0.0, 0.0);
            const double exact = boxIntegral(x, -12.0, rho);
            EXPECT_NEAR(map.depth(g.indexToWorld(pIndex)), exact, 0.02 * exact + 0.01) << x;
            EXPECT_NEAR(detail::pointShadowDepth(g, accessor, pIndex, light.position, 0.25, 0.0, boxMin, boxMax), exact, 0.01 * exact + 0.01) << x;
        }
        // Off the axis, the chord through the box towards the light (both the map and the ray).
        for (int n = 0; n < 50; ++n) {
            const Vec3d pIndex(inside(random), inside(random), inside(random));
            const double ray = detail::pointShadowDepth(g, accessor, pIndex, light.position, 0.1, 0.0, boxMin, boxMax);
            EXPECT_NEAR(map.depth(g.indexToWorld(pIndex)), ray, 0.03 * ray + 0.02) << pIndex.x << " " << pIndex.y << " " << pIndex.z;
        }
    }
}

TEST(PointLight, FallsOffAsTheInverseSquareAndSpotsLightTheirConeOnly)
{
    // 1 / (r^2 + R^2), R the larger of the radius and half a voxel.
    PointLight light = pointAt(Vec3d(1.0, 2.0, 3.0), 5.0);
    EXPECT_DOUBLE_EQ(detail::pointLightFalloff(light, Vec3d(1.0, 2.0, 7.0), 0.1), 1.0 / (16.0 + 0.0025));
    EXPECT_DOUBLE_EQ(detail::pointLightFalloff(light, Vec3d(1.0, 2.0, 3.0), 0.1), 1.0 / 0.0025) << "finite at the light";
    light.radius = 0.5;
    EXPECT_DOUBLE_EQ(detail::pointLightFalloff(light, Vec3d(1.0, 2.3, 3.0), 0.1), 1.0 / (0.09 + 0.25));
    // A 60-degree spot aimed down -z: its edge at 30 degrees off the axis.
    PointLight spot = pointAt(Vec3d(0.0), 1.0);
    spot.spotAngle = 60.0;
    spot.spotTarget = Vec3d(0.0, 0.0, -5.0);
    spot.spotBlend = 0.0;
    const auto at = [](double degrees) { return 2.0 * Vec3d(std::sin(degrees * M_PI / 180.0), 0.0, -std::cos(degrees * M_PI / 180.0)); };
    const double inverseSquare = 1.0 / (4.0 + 0.0025);
    EXPECT_DOUBLE_EQ(detail::pointLightFalloff(spot, at(29.0), 0.1), inverseSquare);
    EXPECT_EQ(detail::pointLightFalloff(spot, at(31.0), 0.1), 0.0);
    EXPECT_EQ(detail::pointLightFalloff(spot, Vec3d(0.0, 0.0, 2.0), 0.1), 0.0) << "behind it";
    // The blend: smoothstep over the cosine's last BLEND fraction of the cone.
    spot.spotBlend = 0.5;
    const double cosEdge = std::cos(M_PI / 6.0), x = 0.3;
    const double degrees = std::acos(cosEdge + x * 0.5 * (1.0 - cosEdge)) * 180.0 / M_PI;
    EXPECT_NEAR(detail::pointLightFalloff(spot, at(degrees), 0.1), inverseSquare * x * x * (3.0 - 2.0 * x), 1e-12);
    EXPECT_DOUBLE_EQ(detail::pointLightFalloff(spot, at(5.0), 0.1), inverseSquare);

    // Rendered: an optically thin blob lit from twice as far is a quarter as bright, in the
    // splatter and in the reference (the blob's size and its shadows aside: within 2 %).
    auto blob = makeFogAround([](const Vec3d& p) { return glm::length(p) - 0.4; }, 0.05, 8, 0.1);
    const CameraSettings camera = lookAtCamera(Vec3d(0.0, 0.0, 4.0), Vec3d(0.0), 48, 48);
    for (const Method method : {Method::Splat, Method::RayMarch}) {
        RenderSettings nearer = pointLit(1.0, {pointAt(Vec3d(3.0, 0.0, 0.0), 9.0)}), farther = nearer;
        farther.pointLights[0].position = Vec3d(6.0, 0.0, 0.0);
        nearer.method = farther.method = method;
        const double ratio = sum(renderGrid(blob, camera, nearer), 1) / sum(renderGrid(blob, camera, farther), 1);
        EXPECT_NEAR(ratio, 4.0, 0.08) << int(method);
    }
    // A spot aimed away from the blob leaves it dark; aimed at it, lights it as a point light.
    RenderSettings away = pointLit(1.0, {pointAt(Vec3d(3.0, 0.0, 0.0), 9.0)}), towards = away, point = away;
    away.pointLights[0].spotAngle = towards.pointLights[0].spotAngle = 40.0;
    away.pointLights[0].spotTarget = Vec3d(3.0, 5.0, 0.0);
    towards.pointLights[0].spotTarget = Vec3d(0.0);
    EXPECT_EQ(sum(renderGrid(blob, camera, away), 1), 0.0);
    EXPECT_NEAR(sum(renderGrid(blob, camera, towards), 1), sum(renderGrid(blob, camera, point), 1), 1e-4 * sum(renderGrid(blob, camera, point), 1));
}

TEST(PointLight, ALightInsideACloudMatchesTheReference)
{
    // An explosion's core: a light at the centre of a dense ball. The splatter lights each
    // (pixel, slab) sample from the light map; the reference marches a shadow ray from every
    // sample to the light. Their pixel sums agree within 3 % and their images closely.
    auto ball = makeFogAround([](const Vec3d& p) { return glm::length(p) - 0.8; }, 1.0, 12, 0.1);
    const CameraSettings camera = lookAtCamera(Vec3d(0.0, 0.0, 3.5), Vec3d(0.0), 48, 48);
    RenderSettings splat = pointLit(0.3, {pointAt(Vec3d(0.05, 0.0, 0.0), 0.5)});
    RenderSettings reference = splat;
    reference.method = Method::RayMarch;
    const Image a = renderGrid(ball, camera, splat), b = renderGrid(ball, camera, reference);
    const double sa = sum(a, 0), sb = sum(b, 0);
    ASSERT_GT(sb, 1.0);
    EXPECT_NEAR(sa / sb, 1.0, 0.03);
    double peak = 0.0;
    for (int y = 0; y < b.height; ++y)
        for (int x = 0; x < b.width; ++x) peak = std::max(peak, double(b.pixel(x, y)[0]));
    EXPECT_LT(rmse(a, b, 0), 0.04 * peak);
    // No light outside the ball, so the shadow is real: the same light with no extinction on its
    // way (a thin ball) is brighter per unit of density.
    RenderSettings unshadowed = splat;
    unshadowed.medium.scatter = Vec3d(0.03);
    EXPECT_GT(sum(renderGrid(ball, camera, unshadowed), 0) * 10.0, 1.3 * sa);

    // The SIMD rasteriser looks the point lights up lane by lane: as the scalar one, its oracle.
    RenderSettings scalar = splat;
    scalar.simd = false;
    EXPECT_LT(maxAbsDiff(a, renderGrid(ball, camera, scalar)), 1e-5);
    // The streamed frame shades as the whole frame does.
    RenderSettings whole = splat;
    whole.cull = false;
    EXPECT_LT(maxAbsDiff(a, renderGrid(ball, camera, whole)), 1e-5);
}

TEST(PointLight, BadLightsAreRefusedOnOneLine)
{
    RenderSettings s;
    s.pointLights = {pointAt(Vec3d(std::nan(""), 0.0, 0.0), 1.0)};
    EXPECT_THROW(s.validate(), ValueError);
    s.pointLights = {pointAt(Vec3d(0.0), -1.0)};
    EXPECT_THROW(s.validate(), ValueError);
    s.pointLights = {pointAt(Vec3d(0.0), 1.0)};
    s.pointLights[0].spotAngle = 200.0;
    EXPECT_THROW(s.validate(), ValueError);
    s.pointLights[0].spotAngle = 30.0;
    s.pointLights[0].spotTarget = Vec3d(0.0);
    EXPECT_THROW(s.validate(), ValueError);
    s.pointLights[0].spotTarget = Vec3d(1.0);
    EXPECT_NO_THROW(s.validate());
}


