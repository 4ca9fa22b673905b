/// @file motion_blur_test.cpp
/// @brief Motion blur and depth of field against closed forms: a moving Gaussian (a Gaussian
///        convolved with a box), a uniform slab moving along and across the view, the thin
///        lens's circle of confusion; still frames bit-identical; the reference's samples.
#include "fixtures.h"
#include "mantaflow_fixture.h"
#include "reference/reference.h"
#include "source/source.h"
#include "support/memory_budget.h"
#include "support/progress.h"

#include <vdb_ewa/ewa_kernel.h>
#include <vdb_ewa/error.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <numeric>
#include <random>
#include <tuple>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

/// A velocity grid that reads @a v everywhere (its background), voxel size @a h.
openvdb::Vec3SGrid::Ptr uniformVelocity(const Vec3d& v, double h)
{
    auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3s(float(v.x), float(v.y), float(v.z)));
    grid->setTransform(openvdb::math::Transform::createLinearTransform(h));
    grid->setName("v");
    return grid;
}

/// A velocity grid that reads @a v on @a density's active voxels and 0 elsewhere, staggered, as
/// a simulation's cache clips its velocities to its density.
openvdb::Vec3SGrid::Ptr clippedVelocity(const openvdb::FloatGrid& density, const Vec3d& v)
{
    auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    grid->setTransform(density.transform().copy());
    grid->setName("velocity");
    grid->setGridClass(openvdb::GRID_STAGGERED);
    grid->tree().topologyUnion(density.tree());
    for (auto it = grid->beginValueOn(); it; ++it) it.setValue(openvdb::Vec3s(float(v.x), float(v.y), float(v.z)));
    return grid;
}

/// PSNR of @a a against @a b over R, G and B, peak 1.
double psnrRgb(const Image& a, const Image& b)
{
    double sum = 0.0;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x)
            for (int c = 0; c < 3; ++c) {
                const double d = double(a.pixel(x, y)[c]) - double(b.pixel(x, y)[c]);
                sum += d * d;
            }
    return -10.0 * std::log10(sum / (3.0 * a.width * a.height));
}

/// Optical depth per pixel, -ln(1 - alpha).
std::vector<double> opticalDepth(const Image& img)
{
    std::vector<double> tau(std::size_t(img.width) * std::size_t(img.height));
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) tau[std::size_t(y) * std::size_t(img.width) + std::size_t(x)] = -std::log1p(-double(img.pixel(x, y)[3]));
    return tau;
}

Frame render(const GridSource& source, const CameraSettings& camera, const RenderSettings& settings, RenderStats* stats = nullptr)
{
    return Renderer(settings).renderFrame(source, Camera(camera, source.worldCentre()), PassRequest{}, stats);
}

double phi(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

/// The streamed frame (@a on, culling) equals the whole frame (culling off) within 1e-5, SIMD and
/// scalar, with no kernel in front of its window; @a check takes both frames' stats each time.
void expectStreamedEqualsWhole(const GridSource& source, const CameraSettings& cam, RenderSettings on,
    const std::function<void(const RenderStats& streamed, const RenderStats& whole)>& check)
{
    RenderSettings off = on;
    off.cull = false;
    for (const bool simd : {true, false}) {
        on.simd = off.simd = simd;
        RenderStats statsOn, statsOff;
        const Frame a = render(source, cam, on, &statsOn), b = render(source, cam, off, &statsOff);
        EXPECT_TRUE(statsOn.streamed);
        check(statsOn, statsOff);
        EXPECT_LT(maxAbsDiff(a.beauty, b.beauty), 1e-5) << "simd " << simd;
        for (const std::string& w : statsOn.warnings) EXPECT_EQ(w.find("in front of their window"), std::string::npos) << w;
    }
}

/// A pure absorber with velocities in world units per frame over a shutter of one frame, in
/// one frame of widened kernels (no sub-frames, no shutter layers: the splatter's own model).
RenderSettings movingAbsorber(double sigma)
{
    RenderSettings s = absorberSettings(sigma);
    s.motionBlur.samples = 1;
    s.motionBlur.layers = 1;
    s.motionBlur.unit = VelocityUnit::Frame;
    s.motionBlur.shutterOpen = -0.5;
    s.motionBlur.shutterClose = 0.5;
    return s;
}

/// A slab of optical depth 4 (40 x 40 x 10 voxels of 0.1) moving 1 unit across an orthographic
/// view (20 pixels a unit), a strip of 8 rows through its middle. The shutter averages images:
/// alpha = f (1 - e^-4) where the slab covers a pixel a share f of the shutter, a linear ramp
/// from x = -2.55 to -1.55.
struct MovingOpaqueSlab
{
    GridSource moving = withVelocityGrid(
        gridSourceFromOpenVDB(makeBoxGrid(openvdb::Coord(-20, -20, 0), openvdb::Coord(19, 19, 9), 2.0f, 0.1)), uniformVelocity(Vec3d(1.0, 0.0, 0.0), 0.1));
    CameraSettings cam = [] {
        CameraSettings c = orthoDownZ(0.0, 0.0, 10.0, 6.0, 120);
        c.height = 8;
        return c;
    }();
    double height = 1.0 - std::exp(-4.0);

    /// The worst and the mean distance of @a f's alpha from the ramp, over its inner 90 %.
    std::pair<double, double> rampErrors(const Frame& f) const
    {
        double worst = 0.0, mean = 0.0;
        int n = 0;
        for (int i = 0; i < 120; ++i) {
            const double x = (i + 0.5 - 60.0) / 20.0;
            if (x < -2.5 || x > -1.6) continue;
            const double e = std::abs(double(f.beauty.pixel(i, 4)[3]) - std::clamp(x + 2.55, 0.0, 1.0) * height);
            worst = std::max(worst, e);
            mean += e;
            ++n;
        }
        return {worst, mean / n};
    }
};

} // namespace

TEST(DepthOfField, AKernelInFocusIsUnchangedAndOffFocusWidensByTheThinLens)
{
    ProjectionParams pinhole;
    pinhole.focalPixels = 800.0;
    pinhole.principalPoint = Vec2d(320.0, 240.0);
    pinhole.antiAliasing = AntiAliasing::Ewa; // adds --lowpass always: the difference is the lens's alone
    ProjectionParams lens = pinhole;
    lens.lens = Sym2{0.25 * 0.05 * 0.05, 0.0, 0.25 * 0.05 * 0.05}; // a disc of radius 0.05: (L/2)^2 I
    lens.focusDepth = 10.0;
    const Mat3d cov(0.04);
    for (const double z : {10.0, 4.0, 25.0}) {
        const Vec3d t(0.3, -0.2, z);
        const Footprint a = projectKernel(t, cov, pinhole), b = projectKernel(t, cov, lens);
        ASSERT_TRUE(a.valid && b.valid);
        // R = f a |1/z - 1/S|, a uniform disc of radius R: variance R^2 / 4 per axis.
        const double r = 800.0 * 0.05 * std::abs(1.0 / z - 1.0 / 10.0);
        EXPECT_NEAR(b.covariance.xx - a.covariance.xx, 0.25 * r * r, 1e-9 * (1.0 + r * r)) << z;
        EXPECT_NEAR(b.covariance.yy - a.covariance.yy, 0.25 * r * r, 1e-9 * (1.0 + r * r)) << z;
        EXPECT_DOUBLE_EQ(b.covariance.xy, a.covariance.xy);
        // The footprint's integral (peak x 2 pi sqrt(det)) is kept: the lens spreads, never dims.
        EXPECT_NEAR(b.peak * std::sqrt(b.covariance.det()), a.peak * std::sqrt(a.covariance.det()), 1e-12 * a.peak * std::sqrt(a.covariance.det()));
        EXPECT_DOUBLE_EQ(b.depth, a.depth);
        if (z == 10.0) {
            EXPECT_EQ(b.covariance.xx, a.covariance.xx); // in focus: bit-identical
            EXPECT_EQ(b.peak, a.peak);
        }
    }
}

TEST(DepthOfField, TheCameraFocusesWhereItLooksAndItsLensRaysMeetThere)
{
    CameraSettings c = lookAtCamera(Vec3d(0.0, 0.0, 12.0), Vec3d(0.0), 64, 48);
    c.fstop = 2.0;
    const Camera camera(c, Vec3d(0.0));
    EXPECT_DOUBLE_EQ(camera.lensRadius(), 50.0 / 4000.0); // focal / (2 fstop), mm as metres
    EXPECT_NEAR(camera.focusDepth(), 12.0, 1e-12);
    EXPECT_EQ(camera.confusionRadius(12.0), 0.0);
    EXPECT_NEAR(camera.confusionRadius(6.0), camera.focalPixels() * camera.lensRadius() * (1.0 / 6.0 - 1.0 / 12.0), 1e-12);
    // Every lens ray through a pixel passes through the pinhole ray's point at the focus depth.
    Vec3d o, d;
    camera.worldRay(10.5, 30.5, o, d);
    const Vec3d forward(0.0, 0.0, -1.0);
    const Vec3d focus = o + d * ((12.0 - c.near) / glm::dot(d, forward));
    for (const auto& [u, v] : {std::pair{1.0, 0.0}, {0.0, -1.0}, {-0.6, 0.6}}) {
        Vec3d lo, ld;
        camera.lensRay(10.5, 30.5, u, v, lo, ld);
        EXPECT_NEAR(glm::length(ld), 1.0, 1e-12);
        EXPECT_NEAR(glm::dot(lo - camera.eye(), forward), c.near, 1e-12); // on the near plane
        const Vec3d at = lo + ld * ((12.0 - c.near) / glm::dot(ld, forward));
        EXPECT_NEAR(glm::length(at - focus), 0.0, 1e-9);
        EXPECT_GT(glm::length(lo - o), 0.0);
    }
    c.focusDistance = 3.0;
    EXPECT_DOUBLE_EQ(Camera(c, Vec3d(0.0)).focusDepth(), 3.0);
    c.projection = Projection::Orthographic;
    EXPECT_THROW(Camera(c, Vec3d(0.0)), ValueError);
    c.projection = Projection::Perspective;
    c.fstop = -1.0;
    EXPECT_THROW(Camera(c, Vec3d(0.0)), ValueError);
}

TEST(MotionBlur, ZeroVelocityIsBitIdenticalToTheStillFrame)
{
    auto grid = makeFogGrid(openvdb::Coord(-6), openvdb::Coord(6), [](const openvdb::Coord& c) { return 0.3f + 0.02f * float(c.x() + 2 * c.y()); }, 0.1);
    const GridSource still = gridSourceFromOpenVDB(grid);
    const GridSource moving = withVelocityGrid(still, uniformVelocity(Vec3d(0.0), 0.1));
    const CameraSettings cam = lookAtCamera(Vec3d(0.4, 0.3, 3.0), Vec3d(0.0), 48, 40);
    const RenderSettings s;
    const Frame a = render(still, cam, s), b = render(moving, cam, s);
    ASSERT_EQ(a.beauty.rgba.size(), b.beauty.rgba.size());
    EXPECT_EQ(0, std::memcmp(a.beauty.rgba.data(), b.beauty.rgba.data(), a.beauty.rgba.size() * sizeof(float)));
}

TEST(MotionBlur, TheLightMovesWithTheMaterial)
{
    // A lit ball moving rigidly 0.3 world units along x (3 voxels), seen at that time (shutter
    // 0.999 to 1.001: moved, hardly blurred): every point carries its light along its path, so the moved
    // ball is the still ball translated, shadows and all, in the splatter (whole and streamed
    // frames, SIMD and scalar; MotionBlur::lightFollows) and in the reference. The light comes
    // along the motion: the still field's shadows looked up where the ball is now (lightFollows
    // false, the faster model) are off by 0.29 (its moved front lit as the unmoved ball's inside).
    auto grid = makeFogGrid(openvdb::Coord(-8), openvdb::Coord(8), [](const openvdb::Coord& c) {
        return std::max(0.0f, 0.8f - 0.1f * float(c.asVec3d().length()));
    }, 0.1);
    const GridSource still = gridSourceFromOpenVDB(grid);
    const Vec3d move(0.3, 0.0, 0.0);
    const GridSource moving = withVelocityGrid(still, uniformVelocity(move, 0.1));
    Mat4d shifted(1.0);
    shifted[3] = glm::dvec4(move, 1.0);
    const GridSource translated = still.transformed(shifted);
    const CameraSettings cam = lookAtCamera(Vec3d(0.15, 0.2, 3.0), Vec3d(0.15, 0.0, 0.0), 48, 40);
    RenderSettings s;
    s.lights[0].direction = Vec3d(-1.0, 0.3, 0.0); // from -x: along the motion
    s.splat.lodPixels = 0.0;
    s.motionBlur.unit = VelocityUnit::Frame;
    s.motionBlur.lightFollows = true;
    s.motionBlur.shutterOpen = 0.999;
    s.motionBlur.shutterClose = 1.001;
    RenderSettings reference = s;
    reference.method = Method::RayMarch;
    reference.step = 0.25;
    for (const bool cull : {true, false}) {
        for (const bool simd : {true, false}) {
            s.cull = cull;
            s.simd = simd;
            EXPECT_LT(maxAbsDiff(render(moving, cam, s).beauty, render(translated, cam, s).beauty), 2e-3) << "cull " << cull << " simd " << simd;
        }
    }
    EXPECT_LT(maxAbsDiff(render(moving, cam, reference).beauty, render(translated, cam, reference).beauty), 2e-3) << "reference";
    s.motionBlur.lightFollows = false;
    EXPECT_GT(maxAbsDiff(render(moving, cam, s).beauty, render(translated, cam, s).beauty), 0.2) << "the still field's light";
}

TEST(MotionBlur, AMovingGaussianIsTheGaussianConvolvedWithItsPath)
{
    // One voxel, no prefilter: one kernel of sigma 0.5 world units seen down -z at 20 pixels a
    // unit (sigma 10 pixels, so the low-pass floor adds nothing). Moving 4 units along x over
    // the shutter, its optical depth is G_y(y) [Phi((x + L/2)/s) - Phi((x - L/2)/s)] / L.
    auto grid = makeBoxGrid(openvdb::Coord(0), openvdb::Coord(0), 0.5f, 1.0);
    const GridSource still = gridSourceFromOpenVDB(grid);
    const double L = 4.0, sigma = 0.5;
    const GridSource moving = withVelocityGrid(still, uniformVelocity(Vec3d(L, 0.0, 0.0), 1.0));
    const int res = 200;
    const CameraSettings cam = orthoDownZ(0.0, 0.0, 10.0, 10.0, res); // 20 pixels a unit
    RenderSettings s = movingAbsorber(0.2);
    s.splat.prefilter = false;
    const std::vector<double> tStill = opticalDepth(render(still, cam, s).beauty);
    // The still peak gives the weight: tau(x, y) = w G(x) G(y), G(0) = 1 / (sqrt(2 pi) sigma).
    const double g0 = 1.0 / (std::sqrt(2.0 * 3.14159265358979323846) * sigma);
    const double w = tStill[std::size_t(res / 2) * res + res / 2] / (g0 * g0);
    const double peak = w * g0 * (2.0 * phi(0.5 * L / sigma) - 1.0) / L;
    // --motion-split s: ceil(L / (s sigma)) sub-paths, within the documented share of the peak
    // (docs/equations.md#motion-blur: 1.2 %, 4.6 % and 11 % at 2, 3 and 4).
    for (const auto& [split, pieces, bound] : {std::tuple{2.0, 4u, 0.02}, {3.0, 3u, 0.05}, {4.0, 2u, 0.12}}) {
        s.motionBlur.splitSigmas = split;
        RenderStats stats;
        const std::vector<double> tMoving = opticalDepth(render(moving, cam, s, &stats).beauty);
        EXPECT_EQ(stats.movingKernels, 1u);
        EXPECT_EQ(stats.motionSubKernels, pieces - 1u) << "split " << split;
        // The mass is kept.
        const double massStill = std::accumulate(tStill.begin(), tStill.end(), 0.0), massMoving = std::accumulate(tMoving.begin(), tMoving.end(), 0.0);
        EXPECT_NEAR(massMoving, massStill, 0.005 * massStill);
        double worst = 0.0;
        for (int y = 60; y < 140; ++y)
            for (int x = 20; x < 180; ++x) {
                const double wx = (x + 0.5 - 0.5 * res) / 20.0, wy = -((y + 0.5 - 0.5 * res) / 20.0); // world x, y of the pixel centre
                const double gy = g0 * std::exp(-0.5 * wy * wy / (sigma * sigma));
                const double expected = w * gy * (phi((wx + 0.5 * L) / sigma) - phi((wx - 0.5 * L) / sigma)) / L;
                worst = std::max(worst, std::abs(tMoving[std::size_t(y) * res + std::size_t(x)] - expected));
            }
        EXPECT_LT(worst, bound * peak) << "split " << split << ", peak " << peak;
        EXPECT_GT(worst, 0.25 * bound * peak) << "split " << split << ": the bound is loose";
    }
}

TEST(MotionBlur, AUniformSlabMovingAlongTheViewKeepsItsImageAndAcrossItRampsItsEdges)
{
    // A slab 40 x 40 x 10 voxels (voxel 0.1) of optical depth 1, seen down -z.
    auto grid = makeBoxGrid(openvdb::Coord(-20, -20, 0), openvdb::Coord(19, 19, 9), 0.5f, 0.1);
    const GridSource still = gridSourceFromOpenVDB(grid);
    const CameraSettings cam = orthoDownZ(0.0, 0.0, 10.0, 6.0, 120); // 20 pixels a unit, 2 a voxel
    const RenderSettings s = movingAbsorber(0.2);
    const std::vector<double> tStill = opticalDepth(render(still, cam, s).beauty);
    // Along the view: the column integral is the same at every shutter time.
    const std::vector<double> tAlong = opticalDepth(render(withVelocityGrid(still, uniformVelocity(Vec3d(0.0, 0.0, 0.8), 0.1)), cam, s).beauty);
    for (std::size_t i = 0; i < tStill.size(); ++i) ASSERT_NEAR(tAlong[i], tStill[i], 2e-3) << i;
    // Across: x moves 1 unit (20 pixels) over the shutter. The slab spans x in [-2.05, 1.95];
    // its left edge becomes a ramp from -2.55 to -1.55, half the interior at -2.05, and the
    // interior (|x| < 1) is unchanged.
    const std::vector<double> tAcross = opticalDepth(render(withVelocityGrid(still, uniformVelocity(Vec3d(1.0, 0.0, 0.0), 0.1)), cam, s).beauty);
    // The splatter blurs optical depth (kernels widen): its ramp is linear in tau
    // (docs/equations.md#motion-blur; the reference's, linear in transmittance, is below).
    const int row = 60;
    const double interior = 1.0; // 0.2 x 0.5 x 10 voxels
    EXPECT_NEAR(tStill[std::size_t(row) * 120 + 60], interior, 0.01); // the lattice's ripple
    const auto at = [&](double worldX) {
        const double px = worldX * 20.0 + 60.0 - 0.5; // pixel centres are at i + 0.5
        const int i = int(std::floor(px));
        const double f = px - i;
        return (1.0 - f) * tAcross[std::size_t(row) * 120 + std::size_t(i)] + f * tAcross[std::size_t(row) * 120 + std::size_t(i + 1)];
    };
    EXPECT_NEAR(at(-2.05), 0.5 * interior, 0.02);
    for (const double x : {-2.35, -2.2, -1.9, -1.75}) EXPECT_NEAR(at(x), interior * (x + 2.55), 0.03) << x; // the box-filtered edge
    // Moving, the lattice's ripple along x is averaged away.
    for (int x = 50; x < 70; ++x) EXPECT_NEAR(tAcross[std::size_t(row) * 120 + std::size_t(x)], interior, 2e-3) << x;
}

TEST(MotionBlur, TheReferenceSamplesTheShutterToTheSameRamp)
{
    auto grid = makeBoxGrid(openvdb::Coord(-20, -20, 0), openvdb::Coord(19, 19, 9), 0.5f, 0.1);
    const GridSource moving = withVelocityGrid(gridSourceFromOpenVDB(grid), uniformVelocity(Vec3d(1.0, 0.0, 0.0), 0.1));
    CameraSettings cam = orthoDownZ(0.0, 0.0, 10.0, 6.0, 120);
    cam.height = 8; // a strip through the slab's middle rows
    RenderSettings s = movingAbsorber(0.2);
    s.method = Method::RayMarch;
    s.step = 0.25;
    s.blurSamples = 64;
    const Frame f = render(moving, cam, s);
    // The image averaged over the shutter: the transmittance is 1 - f (1 - e^-1) where the slab
    // covers the pixel a share f of the shutter. The trilinear field's edge is a voxel-wide ramp
    // about x = -2.05; moved over [-0.5, 0.5], f = clamp(x + 2.55, 0, 1), rounded within 0.05 of
    // the ramp's ends.
    const int row = 4;
    const auto transmittance = [&](int i) { return 1.0 - double(f.beauty.pixel(i, row)[3]); };
    EXPECT_NEAR(transmittance(60), std::exp(-1.0), 0.01);
    for (int i = 0; i < 120; ++i) {
        const double x = (i + 0.5 - 60.0) / 20.0;
        if (x < -2.6 || x > -1.5) continue;
        const double covered = std::clamp(x + 2.55, 0.0, 1.0);
        EXPECT_NEAR(transmittance(i), 1.0 - covered * (1.0 - std::exp(-1.0)), 0.04) << x;
    }
}

TEST(MotionBlur, TheReferenceMovesMaterialWhereItsVelocityGridEnds)
{
    // A simulation's velocities stop where its density does. The slab moves 1 unit across the
    // view over the shutter: its leading edge moves into empty space, where the velocity grid
    // reads 0. Both edges ramp over the shutter as with a velocity grid that fills space: the
    // trailing one, x = -2.05 + t, covers x a share clamp(x + 2.55, 0, 1) of the shutter; the
    // leading one, x = 1.95 + t, a share clamp(2.45 - x, 0, 1). (Looking the velocity up at the
    // sample, as the reference did, left the leading edge where it stood.)
    auto grid = makeBoxGrid(openvdb::Coord(-20, -20, 0), openvdb::Coord(19, 19, 9), 0.5f, 0.1);
    const GridSource moving = withVelocityGrid(gridSourceFromOpenVDB(grid), clippedVelocity(*grid, Vec3d(1.0, 0.0, 0.0)));
    CameraSettings cam = orthoDownZ(0.0, 0.0, 10.0, 6.0, 120);
    cam.height = 8;
    RenderSettings s = movingAbsorber(0.2);
    s.method = Method::RayMarch;
    s.step = 0.25;
    s.blurSamples = 64;
    const Frame f = render(moving, cam, s);
    const auto transmittance = [&](int i) { return 1.0 - double(f.beauty.pixel(i, 4)[3]); };
    for (int i = 0; i < 120; ++i) {
        const double x = (i + 0.5 - 60.0) / 20.0;
        if (std::abs(x + 2.05) > 0.55 && std::abs(x - 1.95) > 0.55) continue;
        const double covered = x < 0.0 ? std::clamp(x + 2.55, 0.0, 1.0) : std::clamp(2.45 - x, 0.0, 1.0);
        EXPECT_NEAR(transmittance(i), 1.0 - covered * (1.0 - std::exp(-1.0)), 0.04) << x;
    }
}

TEST(MotionBlur, TheReferencesMovedVoxelsStopAtACancel)
{
    // The reference indexes its moved voxels slice by slice (up to 1024 point indexes): a
    // cancel is checked between slices, so a render cancelled there does not wait for all.
    auto grid = makeBoxGrid(openvdb::Coord(-20, -20, 0), openvdb::Coord(19, 19, 9), 0.5f, 0.1);
    const GridSource moving = withVelocityGrid(gridSourceFromOpenVDB(grid), clippedVelocity(*grid, Vec3d(1.0, 0.0, 0.0)));
    RenderSettings s = movingAbsorber(0.2);
    const detail::MemoryBudget budget(1e9, "test");
    const detail::MovedVoxels built(moving.impl(), *grid, s, budget, nullptr);
    EXPECT_GT(built.slices(), 1) << "a path of 10 voxels needs several slices";
    Interrupter cancelled;
    cancelled.cancel();
    const detail::Progress progress(&cancelled);
    EXPECT_THROW(detail::MovedVoxels(moving.impl(), *grid, s, budget, &progress), Cancelled);
}

TEST(MotionBlur, StaggeredVelocitiesAreReadAtTheirFaces)
{
    // A uniform shear flow with a strain, v = A x + b (world units, voxels of 0.25), stored as a
    // MAC grid: each component at its face centre, x at (i - 1/2, j, k), y at (i, j - 1/2, k),
    // z at (i, j, k - 1/2). Trilinear reading is exact for a linear field, so the sampler reads
    // A x + b anywhere inside; read at the voxel centres instead, v_x would be off by
    // A_xx h / 2 = 0.0375 and v_y by 0.05.
    const double h = 0.25;
    const Mat3d A(0.3, 0.0, 0.0, 2.0, -0.4, 0.0, 0.5, 0.0, 0.1); // columns: d v / dx, d v / dy, d v / dz
    const Vec3d b(1.0, -2.0, 0.5);
    const auto flow = [&](const Vec3d& x) { return A * x + b; };
    auto velocity = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    velocity->setTransform(openvdb::math::Transform::createLinearTransform(h));
    velocity->setGridClass(openvdb::GRID_STAGGERED);
    auto density = makeBoxGrid(openvdb::Coord(-8), openvdb::Coord(7), 0.5f, h);
    auto acc = velocity->getAccessor();
    for (int i = -10; i <= 10; ++i)
        for (int j = -10; j <= 10; ++j)
            for (int k = -10; k <= 10; ++k) {
                const Vec3d c(i * h, j * h, k * h);
                acc.setValue(openvdb::Coord(i, j, k), openvdb::Vec3s(float(flow(c - Vec3d(0.5 * h, 0, 0)).x), float(flow(c - Vec3d(0, 0.5 * h, 0)).y),
                                                          float(flow(c - Vec3d(0, 0, 0.5 * h)).z)));
            }
    const GridSource source = withVelocityGrid(gridSourceFromOpenVDB(density), velocity);
    detail::VelocitySampler sampler(source.impl());
    std::mt19937 random(7);
    std::uniform_real_distribution<double> inside(-2.0, 2.0);
    for (int n = 0; n < 200; ++n) {
        const Vec3d x(inside(random), inside(random), inside(random));
        const Vec3d v = sampler.at(x), expected = flow(x);
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(v[a], expected[a], 2e-5) << a << " at " << x.x << "," << x.y << "," << x.z;
    }
    // At a voxel centre (the splatter's kernels): the same.
    const Vec3d centre = sampler.atIndex(Vec3d(2.0, -3.0, 1.0)), expected = flow(Vec3d(2.0 * h, -3.0 * h, h));
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(centre[a], expected[a], 2e-5) << a;
}

TEST(MotionBlur, BothIntegratorsAgreeOnAMantaflowLikeFire)
{
    // A fire laid out as Mantaflow writes it (mantaflow_fixture.h), its velocities read in their
    // own unit (--velocity-scale 2.5 x the voxel: 3 voxels of travel over a frame): the splatter
    // agrees with the reference on the blurred frame as on the still frame, at `default` (one
    // sweep, three shutter layers, each lit where its own material came from) within 1 dB and
    // at `high` (sub-frames) within 0.5 dB, and the blur shows.
    const MantaflowFire fire;
    const GridSource still = withEmissionGrid(gridSourceFromOpenVDB(fire.density), fire.flame);
    const GridSource moving = withVelocityGrid(still, fire.velocity);
    CameraSettings cam;
    cam.width = 80;
    cam.height = 45;
    cam.translate = Vec3d(3.5, 0.575, 0.575);
    cam.lookAt = Vec3d(0.575, 0.575, 0.575);
    // default: 37.7 against 38.0 dB; each layer lit by the layers' mean move instead: 30.9.
    // high: 40.2 against 38.6 dB; the reference that looked the velocity up at its samples: 0.9 below.
    for (const auto& [quality, name, margin] : {std::tuple{Quality::Default, "default", 1.0}, std::tuple{Quality::High, "high", 0.5}}) {
        RenderSettings splat = RenderSettings::preset(quality);
        splat.gridEmission.color = Vec3d(1.0, 0.35, 0.08);
        splat.gridEmission.intensity = 3.0;
        splat.motionBlur.shutterOpen = -0.5;
        splat.motionBlur.shutterClose = 0.5;
        splat.motionBlur.velocityScale = MantaflowFire::kSecondsScale;
        RenderSettings reference = splat;
        reference.method = Method::RayMarch;
        reference.step = 0.25;
        reference.blurSamples = 32;
        const Frame stillSplat = render(still, cam, splat), stillReference = render(still, cam, reference);
        const Frame movingSplat = render(moving, cam, splat), movingReference = render(moving, cam, reference);
        const double stillAgreement = psnrRgb(stillSplat.beauty, stillReference.beauty), movingAgreement = psnrRgb(movingSplat.beauty, movingReference.beauty);
        std::printf("Mantaflow-like fire at %s: still %.1f dB, blurred %.1f dB; the reference's blur %.1f dB\n", name,
            stillAgreement, movingAgreement, psnrRgb(stillReference.beauty, movingReference.beauty));
        EXPECT_GT(movingAgreement, stillAgreement - margin) << name;
        EXPECT_LT(psnrRgb(stillReference.beauty, movingReference.beauty), stillAgreement - 3.0) << "the blur shows";
    }
}

TEST(MotionBlur, TheStreamedFrameEqualsTheWholeFrame)
{
    auto grid = makeFogGrid(openvdb::Coord(-12), openvdb::Coord(12), [](const openvdb::Coord& c) { return 0.4f + 0.03f * float(c.x() - c.z()); }, 0.1);
    auto velocity = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    velocity->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
    auto acc = velocity->getAccessor();
    for (int i = -12; i <= 12; ++i)
        for (int j = -12; j <= 12; ++j)
            for (int k = -12; k <= 12; ++k) acc.setValueOn(openvdb::Coord(i, j, k), openvdb::Vec3s(0.2f * float(j), -0.5f, 0.1f * float(i)));
    const GridSource moving = withVelocityGrid(gridSourceFromOpenVDB(grid), velocity);
    const CameraSettings cam = lookAtCamera(Vec3d(0.5, 0.4, 3.5), Vec3d(0.0), 64, 48);
    RenderSettings on;
    on.motionBlur.fps = 4.0; // long paths: sub-kernels
    on.motionBlur.lightFollows = true; // the moves carried through windows, light on demand padded by them
    expectStreamedEqualsWhole(moving, cam, on, [](const RenderStats& streamed, const RenderStats& whole) {
        EXPECT_GT(streamed.motionSubKernels, 0u);
        EXPECT_EQ(streamed.motionSubKernels, whole.motionSubKernels);
    });
    // The sub-frames share one sweep (each window's bricks expanded once for all of them);
    // where their images do not fit in half the budget, they are rendered one after the other,
    // to the same image.
    on.motionBlur.samples = 4;
    on.splat.pixelSize = 1; // every pixel's images (larger pixels would fit in the budget)
    const CameraSettings large = lookAtCamera(Vec3d(0.5, 0.4, 3.5), Vec3d(0.0), 400, 300);
    RenderStats one, several;
    const Frame a = render(moving, large, on, &one);
    RenderSettings tight = on;
    tight.maxMemory = 64.0 * 1024.0 * 1024.0; // 4 images of 400 x 300 pixels at 96 bytes a pixel: 46 MB, above half of it
    const Frame b = render(moving, large, tight, &several);
    EXPECT_TRUE(one.streamed);
    EXPECT_TRUE(several.streamed);
    EXPECT_EQ(one.bricksExpanded + one.bricksHidden, one.bricks - one.bricksOutside) << "each brick once";
    EXPECT_EQ(several.bricksExpanded + several.bricksHidden, 4u * (several.bricks - several.bricksOutside)) << "each brick in each sub-frame";
    EXPECT_EQ(one.motionSubKernels, several.motionSubKernels);
    EXPECT_LT(maxAbsDiff(a.beauty, b.beauty), 1e-5);
}

TEST(MotionBlur, DoubleVelocitiesMoveAsFloatOnesAndOtherGridsAreRefused)
{
    auto grid = makeFogGrid(openvdb::Coord(-4), openvdb::Coord(4), [](const openvdb::Coord& c) { return 0.3f + 0.05f * float(c.y() & 1); }, 0.1);
    const GridSource still = gridSourceFromOpenVDB(grid);
    auto d = openvdb::Vec3DGrid::create(openvdb::Vec3d(0.0, 0.0, 0.0));
    d->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
    auto s = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    s->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
    for (int i = -4; i <= 4; ++i) {
        d->tree().setValueOn(openvdb::Coord(i, 0, 0), openvdb::Vec3d(8.0, 4.0 * i, 0.0));
        s->tree().setValueOn(openvdb::Coord(i, 0, 0), openvdb::Vec3s(8.0f, 4.0f * float(i), 0.0f));
    }
    const CameraSettings cam = lookAtCamera(Vec3d(0.0, 0.0, 3.0), Vec3d(0.0), 32, 32);
    const Frame a = render(withVelocityGrid(still, d), cam, RenderSettings()), b = render(withVelocityGrid(still, s), cam, RenderSettings());
    EXPECT_EQ(0, std::memcmp(a.beauty.rgba.data(), b.beauty.rgba.data(), a.beauty.rgba.size() * sizeof(float)));
    EXPECT_GT(maxAbsDiff(a.beauty, render(still, cam, RenderSettings()).beauty), 1e-3);
    EXPECT_THROW(withVelocityGrid(still, grid), InputError);
    EXPECT_THROW(withVelocityGrid(still, nullptr), InputError);
    EXPECT_THROW(still.withVelocityGrid("v"), InputError); // a host grid has no file
}

TEST(MotionBlur, AbsurdVelocitiesAreClampedAndSaid)
{
    auto grid = makeBoxGrid(openvdb::Coord(-2), openvdb::Coord(2), 0.5f, 0.1);
    const GridSource moving = withVelocityGrid(gridSourceFromOpenVDB(grid), uniformVelocity(Vec3d(1e30, 0.0, std::nan("")), 0.1));
    RenderStats stats;
    const Frame f = render(moving, lookAtCamera(Vec3d(0.0, 0.0, 3.0), Vec3d(0.0), 32, 32), RenderSettings(), &stats);
    for (const float v : f.beauty.rgba) ASSERT_TRUE(std::isfinite(v));
    bool said = false;
    for (const std::string& w : stats.warnings) said = said || w.find("4096 voxel lengths") != std::string::npos;
    EXPECT_TRUE(said);
}

TEST(MotionBlur, SettingsOutOfRangeAreRefused)
{
    RenderSettings s;
    s.motionBlur.shutterOpen = 0.5;
    s.motionBlur.shutterClose = 0.0;
    EXPECT_THROW(Renderer{s}, ValueError);
    s = RenderSettings();
    s.motionBlur.fps = 0.0;
    EXPECT_THROW(Renderer{s}, ValueError);
    s = RenderSettings();
    s.motionBlur.velocityScale = std::nan("");
    EXPECT_THROW(Renderer{s}, ValueError);
    s = RenderSettings();
    s.blurSamples = 0;
    EXPECT_THROW(Renderer{s}, ValueError);
    for (const double split : {0.4, 65.0, std::nan("")}) {
        s = RenderSettings();
        s.motionBlur.splitSigmas = split;
        EXPECT_THROW(Renderer{s}, ValueError) << split;
    }
}

TEST(DepthOfField, TheSplatterMatchesTheReferenceOffFocus)
{
    // A blob 1 unit wide 3 units behind the focus: the lens blurs it by R = f a (1/9 - 1/12).
    auto grid = makeFogGrid(openvdb::Coord(-5), openvdb::Coord(5), [](const openvdb::Coord& c) {
        return float(std::exp(-0.5 * double(c.x() * c.x() + c.y() * c.y() + c.z() * c.z()) / 4.0)); }, 0.1);
    const GridSource blob = gridSourceFromOpenVDB(grid);
    CameraSettings cam = lookAtCamera(Vec3d(0.0, 0.0, 12.0), Vec3d(0.0), 96, 96);
    cam.setFieldOfView(8.0);
    cam.fstop = 0.25;
    cam.focusDistance = 9.0;
    // Optically thin: the splatter blurs optical depth, the lens averages images, and the two
    // agree where exp(-tau) is linear (docs/equations.md#depth-of-field).
    RenderSettings s = absorberSettings(0.1);
    RenderSettings r = s;
    r.method = Method::RayMarch;
    r.step = 0.1;
    r.blurSamples = 128;
    const std::vector<double> a = opticalDepth(render(blob, cam, s).beauty), b = opticalDepth(render(blob, cam, r).beauty);
    ASSERT_EQ(a.size(), b.size());
    CameraSettings pin = cam;
    pin.fstop = 0.0;
    const std::vector<double> sharp = opticalDepth(render(blob, pin, s).beauty);
    double err = 0.0, spread = 0.0, peak = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        err += (a[i] - b[i]) * (a[i] - b[i]);
        spread += (sharp[i] - b[i]) * (sharp[i] - b[i]);
        peak = std::max(peak, b[i]);
    }
    err = std::sqrt(err / double(a.size()));
    spread = std::sqrt(spread / double(a.size()));
    EXPECT_LT(err, 0.02 * peak);
    EXPECT_GT(spread, 5.0 * err); // the lens's blur is large against what is left
}

TEST(DepthOfField, LevelSetsRenderInFocusAndSaySo)
{
    // A level set's coverage comes from its discs, which the lens would not blur: in focus.
    const GridSource sphere = gridSourceFromOpenVDB(sphereLevelSet(1.0, 0.05));
    CameraSettings cam = lookAtCamera(Vec3d(0.0, 0.0, 5.0), Vec3d(0.0), 48, 48);
    const Frame sharp = render(sphere, cam, RenderSettings());
    cam.fstop = 0.02;
    cam.focusDistance = 2.0;
    RenderStats stats;
    const Frame lens = render(sphere, cam, RenderSettings(), &stats);
    EXPECT_EQ(0, std::memcmp(sharp.beauty.rgba.data(), lens.beauty.rgba.data(), sharp.beauty.rgba.size() * sizeof(float)));
    bool said = false;
    for (const std::string& w : stats.warnings) said = said || w.find("--fstop changes nothing here") != std::string::npos;
    EXPECT_TRUE(said);
}

TEST(MotionBlur, SubFramesConvergeToTheShuttersAverageOfAnOpaqueEdge)
{
    // MovingOpaqueSlab: one frame of widened kernels blurs optical depth instead of averaging
    // images (an edge nearly as sharp, moved out); sub-frames (--motion-samples) converge to the
    // average.
    const MovingOpaqueSlab slab;
    const GridSource& moving = slab.moving;
    const CameraSettings& cam = slab.cam;
    RenderSettings s = movingAbsorber(0.2);
    const auto error = [&](int samples) {
        s.motionBlur.samples = samples;
        return slab.rampErrors(render(moving, cam, s)).first;
    };
    const double one = error(1), sixteen = error(16);
    EXPECT_GT(one, 0.2);
    EXPECT_LT(sixteen, 0.04);
    s.motionBlur.samples = 4;
    EXPECT_THROW(Renderer(s).renderFrame(moving, Camera(cam, moving.worldCentre()), [] { PassRequest p; p.deep = true; return p; }()), ValueError);
}

TEST(MotionBlur, ShutterLayersApproachTheShuttersAverageOfAnOpaqueEdgeInOneSweep)
{
    // MovingOpaqueSlab's ramp in one sweep: with L shutter layers each pixel sees the slab
    // cover it in each 1/L of the shutter it covers, a staircase of L steps along the ramp, each
    // step smoothed by its sub-kernels' box (mean error at most 1/(2L) of the ramp's height;
    // docs/equations.md#shutter-layers).
    const MovingOpaqueSlab slab;
    const GridSource& moving = slab.moving;
    const CameraSettings& cam = slab.cam;
    const double height = slab.height;
    RenderSettings s = movingAbsorber(0.2);
    const auto errors = [&](int layers, bool simd, RenderStats* stats = nullptr) {
        s.motionBlur.layers = layers;
        s.simd = simd;
        const Frame f = render(moving, cam, s, stats);
        // Inside the slab, every layer opaque: alpha as without motion.
        EXPECT_NEAR(f.beauty.pixel(60, 4)[3], height, 1e-3) << layers;
        return slab.rampErrors(f);
    };
    for (const bool simd : {true, false}) {
        RenderStats stats;
        const auto [worst1, mean1] = errors(1, simd);
        const auto [worst2, mean2] = errors(2, simd, &stats);
        const auto [worst4, mean4] = errors(4, simd);
        const auto [worst8, mean8] = errors(8, simd);
        EXPECT_GT(mean1, 0.15);
        EXPECT_LT(worst2, worst1);
        EXPECT_LT(worst4, worst2);
        for (const auto& [layers, mean] : {std::pair{2, mean2}, {4, mean4}, {8, mean8}}) EXPECT_LT(mean, height / (2.0 * layers)) << layers;
        EXPECT_LT(worst8, 0.1);
        EXPECT_GT(stats.motionSubKernels, 0u); // the paths split, each piece in its layers
    }
    // The SIMD backend composites the layers as the scalar one does.
    s.motionBlur.layers = 4;
    s.simd = true;
    const Frame simd = render(moving, cam, s);
    s.simd = false;
    EXPECT_LT(maxAbsDiff(simd.beauty, render(moving, cam, s).beauty), 1e-5);
}

TEST(DepthOfField, LensPartsTileTheDiscWithTheirClosedFormMoments)
{
    // The whole disc, a half and a quarter of it: centroid 4 / (3 pi) from the centre along the
    // part's middle, variance 1/4 across it and 1/4 - (4 / (3 pi))^2 along it (a half disc).
    const double c = 4.0 / (3.0 * 3.14159265358979323846);
    const LensPart whole = lensPart(0, 1);
    EXPECT_NEAR(glm::length(whole.centroid), 0.0, 1e-15);
    EXPECT_NEAR(whole.covariance[0][0], 0.25, 1e-15);
    EXPECT_NEAR(whole.covariance[1][1], 0.25, 1e-15);
    EXPECT_NEAR(whole.covariance[1][0], 0.0, 1e-15);
    const LensPart half = lensPart(0, 2); // the upper half, y > 0
    EXPECT_NEAR(half.centroid.x, 0.0, 1e-15);
    EXPECT_NEAR(half.centroid.y, c, 1e-15);
    EXPECT_NEAR(half.covariance[0][0], 0.25, 1e-15);
    EXPECT_NEAR(half.covariance[1][1], 0.25 - c * c, 1e-15);
    const LensPart quarter = lensPart(0, 4); // x > 0, y > 0
    EXPECT_NEAR(quarter.centroid.x, c, 1e-15);
    EXPECT_NEAR(quarter.centroid.y, c, 1e-15);
    EXPECT_NEAR(quarter.covariance[0][0], 0.25 - c * c, 1e-15);
    EXPECT_NEAR(quarter.covariance[1][0], 1.0 / (2.0 * 3.14159265358979323846) - c * c, 1e-15); // E[xy] = 1 / (2 pi) on the quarter
    // Any count: equal parts whose centroids average to the centre and whose second moments
    // about the centre average to the disc's, (1/4) I (the parts tile it).
    for (const int parts : {1, 2, 3, 5, 7, 8, 16, 24, 32, 64}) {
        Vec2d mean(0.0);
        Mat2d second(0.0);
        for (int k = 0; k < parts; ++k) {
            const LensPart p = lensPart(k, parts);
            mean += p.centroid / double(parts);
            second += (p.covariance + glm::outerProduct(p.centroid, p.centroid)) / double(parts);
            EXPECT_GE(p.covariance[0][0] * p.covariance[1][1] - p.covariance[1][0] * p.covariance[1][0], -1e-15) << parts;
            EXPECT_LT(p.covariance[0][0] + p.covariance[1][1], parts == 1 ? 0.5 + 1e-15 : 0.5) << parts;
        }
        EXPECT_NEAR(glm::length(mean), 0.0, 1e-14) << parts;
        EXPECT_NEAR(second[0][0], 0.25, 1e-14) << parts;
        EXPECT_NEAR(second[1][1], 0.25, 1e-14) << parts;
        EXPECT_NEAR(second[1][0], 0.0, 1e-14) << parts;
    }
    // More parts leave less of the lens to each: 16 parts keep under a tenth of the variance.
    double largest = 0.0;
    for (int k = 0; k < 16; ++k) largest = std::max(largest, lensPart(k, 16).covariance[0][0] + lensPart(k, 16).covariance[1][1]);
    EXPECT_LT(largest, 0.05);
    EXPECT_THROW(lensPart(2, 2), ValueError);
}

TEST(DepthOfField, ASubApertureSeesTheFocusPlaneWhereTheLensDoesAndTheRestFromItsPoint)
{
    CameraSettings c = lookAtCamera(Vec3d(0.3, -0.2, 12.0), Vec3d(0.0), 64, 48);
    c.fstop = 0.5;
    c.focusDistance = 8.0;
    const Camera camera(c, Vec3d(0.0));
    const double l = camera.lensRadius();
    EXPECT_EQ(camera.throughLensPart(0, 1).eye(), camera.eye());
    for (const int parts : {2, 5, 16}) {
        for (int k = 0; k < parts; ++k) {
            const Camera sub = camera.throughLensPart(k, parts);
            const LensPart part = lensPart(k, parts);
            for (const Vec3d& t : {Vec3d(0.4, -0.3, 8.0), Vec3d(-0.7, 0.2, 8.0), Vec3d(0.4, -0.3, 4.0), Vec3d(1.0, 0.5, 20.0)}) {
                const Vec3d world = camera.eye() + glm::transpose(camera.cameraFromWorld()) * t;
                const Vec2d seen = sub.rasterFromCamera(sub.cameraFromWorldPoint(world));
                // From the lens point e = l centroid, through the thin lens: the pinhole's image
                // plus the parallax of the depth against the focus depth.
                const Vec2d e = l * part.centroid;
                const Vec2d expected = camera.principalPoint() +
                    camera.focalPixels() * (Vec2d(t.x - e.x, t.y - e.y) / t.z + e / camera.focusDepth());
                EXPECT_NEAR(glm::length(seen - expected), 0.0, 1e-9) << parts << " " << k;
                if (t.z == 8.0) {
                    EXPECT_NEAR(glm::length(seen - camera.rasterFromCamera(t)), 0.0, 1e-9);
                }
            }
            EXPECT_NEAR(sub.lensCovariance()[0][0], l * l * part.covariance[0][0], 1e-15);
            // A part is no wider than the lens in any direction; 16 parts are narrower in all.
            EXPECT_LE(sub.confusionRadius(4.0), camera.confusionRadius(4.0) * (1.0 + 1e-12));
            if (parts == 16) {
                EXPECT_LT(sub.confusionRadius(4.0), 0.5 * camera.confusionRadius(4.0));
            }
        }
    }
}

TEST(DepthOfField, LensSamplesConvergeToTheLenssAverageOfAThickEdge)
{
    // A thin slab of optical depth 4 with a straight edge, far behind the focus (circle of
    // confusion about 12 pixels). The lens averages images: the edge's alpha ramps over the
    // disc. One frame of widened kernels blurs optical depth: the edge stays steep, dilated.
    // Sub-apertures (--lens-samples) converge to the reference's lens samples (1024 a pixel).
    auto grid = makeBoxGrid(openvdb::Coord(-60, -60, 0), openvdb::Coord(-1, 59, 1), 10.0f, 0.05);
    const GridSource slab = gridSourceFromOpenVDB(grid);
    CameraSettings cam = lookAtCamera(Vec3d(0.0, 0.0, 10.0), Vec3d(0.0), 120, 8);
    cam.setFieldOfView(30.0);
    cam.focusDistance = 5.0;
    const double f = 0.5 * 120 / std::tan(15.0 * 3.14159265358979323846 / 180.0), lens = 12.0 / (f * 0.1);
    cam.fstop = cam.focal / (2000.0 * lens); // R = f L |1/10 - 1/5| = 12 pixels
    RenderSettings s = absorberSettings(0.2);
    RenderSettings r = s;
    r.method = Method::RayMarch;
    r.step = 0.25;
    r.blurSamples = 1024;
    const Image truth = render(slab, cam, r).beauty;
    const auto error = [&](int samples) {
        s.lensSamples = samples;
        const Image image = render(slab, cam, s).beauty;
        double worst = 0.0;
        for (int i = 0; i < 120; ++i) worst = std::max(worst, std::abs(double(image.pixel(i, 4)[3]) - double(truth.pixel(i, 4)[3])));
        return worst;
    };
    // Measured: 0.37, 0.19, 0.090 and 0.049 with 1, 4, 16 and 64 parts: each part's own
    // optical-depth blur shrinks with its size, about as 1 / sqrt(parts).
    const double one = error(1), four = error(4), sixteen = error(16);
    EXPECT_GT(truth.pixel(30, 4)[3], 0.95);  // the slab, well inside
    EXPECT_LT(truth.pixel(90, 4)[3], 0.05);  // beyond the disc's reach
    EXPECT_GT(one, 0.3);
    EXPECT_LT(four, 0.6 * one);
    EXPECT_LT(sixteen, 0.6 * four);
    EXPECT_LT(sixteen, 0.1);
    // A deep image has no average: one frame through the whole lens, and a warning says so.
    PassRequest deep;
    deep.deep = true;
    RenderStats said;
    s.lensSamples = 4;
    const Frame parts = Renderer(s).renderFrame(slab, Camera(cam, slab.worldCentre()), deep, &said);
    s.lensSamples = 1;
    const Frame whole = Renderer(s).renderFrame(slab, Camera(cam, slab.worldCentre()), deep);
    EXPECT_EQ(maxAbsDiff(parts.beauty, whole.beauty), 0.0f);
    std::string warnings;
    for (const std::string& w : said.warnings) warnings += w + "\n";
    EXPECT_NE(warnings.find("--deep: one frame through the whole lens"), std::string::npos) << warnings;
}

TEST(DepthOfField, TheStreamedFrameEqualsTheWholeFrameThroughEachSubAperture)
{
    // A dense block overflowing the frame, seen through four sub-apertures: each part's eye and
    // principal point move, and the streamed frame's brick bounds and opaque tiles must follow.
    auto grid = makeFogGrid(openvdb::Coord(-24), openvdb::Coord(24), [](const openvdb::Coord& c) { return 0.6f + 0.01f * float(c.x() - c.z()); }, 0.05);
    const GridSource block = gridSourceFromOpenVDB(grid);
    CameraSettings cam = lookAtCamera(Vec3d(0.3, 0.2, 3.0), Vec3d(0.0), 128, 96);
    cam.fstop = 0.02;
    cam.focusDistance = 2.2; // the parts' principal points move by up to 40 pixels
    RenderSettings on;
    on.lensSamples = 4;
    expectStreamedEqualsWhole(block, cam, on, [](const RenderStats& streamed, const RenderStats&) {
        EXPECT_GT(streamed.bricksHidden, 0u) << "opaque tiles hide bricks (in every sub-aperture)";
    });
}
