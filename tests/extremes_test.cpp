/// @file extremes_test.cpp
/// @brief Numerical extremes (ewa-brief Sec. 8, docs/numerics.md): no crash, no NaN or Inf,
///        a warning for what was clamped or skipped, and agreement with the ray-march
///        reference (--method raymarch) where the case is well posed.
#include "fixtures.h"

#include "projection/projection.h"
#include "raster/raster.h"
#include "support/memory_budget.h"

#include <gtest/gtest.h>

#include <openvdb/math/Maps.h>

#include <chrono>
#include <cstdio>
#include <limits>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

/// Every pixel finite, alpha in [0, 1], colour >= 0.
void expectSane(const Image& img)
{
    ASSERT_TRUE(img.allFinite());
    for (std::size_t i = 0; i < img.rgba.size(); ++i) {
        if (i % 4 == 3) {
            ASSERT_GE(img.rgba[i], 0.0f);
            ASSERT_LE(img.rgba[i], 1.0f);
        } else {
            ASSERT_GE(img.rgba[i], 0.0f);
        }
    }
}

std::string allWarnings(const RenderStats& s)
{
    std::string all;
    for (const auto& w : s.warnings) all += w + "\n";
    return all;
}

/// Render with the splatter and the reference; both sane; alpha and red RMSE below @a tolerance.
RenderStats expectMatchesReference(const openvdb::FloatGrid::Ptr& grid, const CameraSettings& cam, double tolerance,
    RenderSettings settings = RenderSettings(), double referenceStep = 0.25, Method reference = Method::RayMarch)
{
    RenderStats stats, refStats;
    const Image splat = renderGrid(grid, cam, settings, &stats);
    settings.method = reference;
    settings.step = referenceStep;
    const Image ref = renderGrid(grid, cam, settings, &refStats);
    expectSane(splat);
    expectSane(ref);
    const double a = rmse(splat, ref, 3), r = rmse(splat, ref, 0);
    std::printf("  splat vs reference: alpha RMSE %.2e, red RMSE %.2e, alpha sums %.1f / %.1f\n", a, r, alphaSum(splat),
        alphaSum(ref));
    EXPECT_LT(a, tolerance);
    EXPECT_LT(r, tolerance);
    EXPECT_GT(alphaSum(ref), 10.0) << "the case is not in view";
    return stats;
}

/// A box of voxels [-n, n)^3 of density rho.
openvdb::FloatGrid::Ptr cube(int n, float rho, double h)
{
    return makeBoxGrid(openvdb::Coord(-n), openvdb::Coord(n - 1), rho, h);
}

} // namespace

TEST(Extremes, NearPlaneCutsTheVolume)
{
    // Near plane through the middle of the cube: both methods drop what lies before it.
    CameraSettings cam = lookAtCamera(Vec3d(0, 0, 3.0), Vec3d(0.0), 64, 48);
    cam.near = 3.0;
    const RenderStats s = expectMatchesReference(cube(16, 0.2f, 0.125), cam, 0.02);
    EXPECT_NE(allWarnings(s).find("in front of the near plane left out"), std::string::npos) << allWarnings(s);
}

TEST(Extremes, CameraInsideTheVolume)
{
    CameraSettings cam = lookAtCamera(Vec3d(0.1, 0.05, 0.3), Vec3d(0.0), 64, 48);
    cam.setFieldOfView(90.0);
    const RenderStats s = expectMatchesReference(cube(16, 0.05f, 0.125), cam, 0.03);
    EXPECT_NE(allWarnings(s).find("around the camera drawn as if a little further away"), std::string::npos) << allWarnings(s);
}

TEST(Extremes, GrazingRaysAtTheFrustumEdge)
{
    // A wide camera with the volume at and beyond the edge of the frame.
    CameraSettings cam = lookAtCamera(Vec3d(0.0), Vec3d(0, 0, -1), 96, 64);
    cam.setFieldOfView(120.0);
    auto grid = makeBoxGrid(openvdb::Coord(14, -4, -12), openvdb::Coord(40, 4, -2), 0.3f, 0.1);
    RenderSettings wide; // kernels wide enough that some beyond 1.3x the edge reach into the frame
    wide.splat.kernelSigma = 0.55;
    const RenderStats s = expectMatchesReference(grid, cam, 0.03, wide);
    EXPECT_NE(allWarnings(s).find("far outside the frame"), std::string::npos) << allWarnings(s);
}

TEST(Extremes, FootprintLargerThanTheImage)
{
    CameraSettings cam = lookAtCamera(Vec3d(0, 0, 3.0), Vec3d(0.0), 48, 32);
    cam.setFieldOfView(10.0);
    // One voxel: the trilinear field is a tent, the splatter's a Gaussian; this case guards the
    // projection of a kernel larger than the frame, so it is measured against the ray march of
    // the same Gaussian, self-emitting (the diagnostic march shades per kernel centre, the
    // splatter per slab sample: with no light the two differ only in the projection).
    RenderSettings emissive;
    emissive.medium.scatter = Vec3d(0.0);
    emissive.medium.absorb = Vec3d(1.6);
    emissive.medium.emission = Vec3d(1.0);
    expectMatchesReference(makeBoxGrid(openvdb::Coord(0), openvdb::Coord(0), 0.5f, 1.0), cam, 0.02, emissive, 0.25,
        Method::RayMarchGaussian);
}

TEST(Extremes, SubPixelFootprintsKeepTheirIntegral)
{
    // 64^3 voxels of 1e-3 at distance 20, each voxel about 0.2 pixel: the low-pass filter
    // dominates every footprint, and the image still holds the optical depth of the cube
    // (Eq. 32, 33: sum over pixels of tau = sigma rho N |det A| / l * f^2 / t2^2 on the axis).
    const double h = 1e-3, sigma = 1e-3, rho = 0.5, distance = 20.0;
    const int n = 32;
    CameraSettings cam = lookAtCamera(Vec3d(-0.5 * h, -0.5 * h, distance), Vec3d(-0.5 * h, -0.5 * h, 0.0), 64, 64);
    const double f = 0.2 * distance / h; // pixels per plane unit for 0.2 pixel voxels
    cam.focal = cam.aperture * f / 64.0;
    RenderStats stats;
    const Image img = renderGrid(cube(n, float(rho), h), cam, absorberSettings(sigma), &stats);
    expectSane(img);
    const double voxels = std::pow(2.0 * n, 3);
    const double expected = sigma * rho * voxels * h * h * h / h * f * f / (distance * distance);
    // alpha = 1 - exp(-tau) with tau <= 0.032 per pixel: about tau (1 - tau / 2).
    EXPECT_NEAR(alphaSum(img), expected, 0.03 * expected);
}

TEST(Extremes, VoxelSizesFrom1eMinus6To1e6AreScaleInvariant)
{
    // The same scene scaled by k renders the same image: densities are per voxel length.
    // OpenVDB refuses any map with |det A| < 3e-15, so uniform voxels stop at about 1.5e-5:
    // the small end is 2e-5 here, and 1e-6 voxels are tested as anisotropic ones below.
    auto render = [](double k) {
        auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(
            openvdb::ConstPtrCast<openvdb::FloatGrid>(makeSampleGrid(SampleGrid::Cloud, 0.08).impl().grid)->deepCopyGrid());
        openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
        m.setToScale(openvdb::Vec3d(0.08 * k));
        grid->setTransform(std::make_shared<openvdb::math::Transform>(std::make_shared<openvdb::math::AffineMap>(m)));
        CameraSettings cam = lookAtCamera(Vec3d(1.5, 0.8, 4.5) * k, Vec3d(0.0), 96, 64);
        cam.near = 1e-3 * k;
        return renderGrid(grid, cam, RenderSettings());
    };
    const Image unit = render(1.0);
    expectSane(unit);
    for (double k : {2e-5 / 0.08, 1e6 / 0.08}) { // voxel sizes 2e-5 and 1e6
        const Image scaled = render(k);
        expectSane(scaled);
        EXPECT_LT(rmse(scaled, unit), 1e-4) << "scale " << k;
    }
}

TEST(Extremes, MicrometreVoxels)
{
    // Voxels of 1e-6 x 1e-6 x 1e-2 (|det A| = 1e-14, above OpenVDB's limit), seen at an angle.
    auto grid = cube(8, 0.5f, 1.0);
    openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
    m.setToScale(openvdb::Vec3d(1e-6, 1e-6, 1e-2));
    grid->setTransform(std::make_shared<openvdb::math::Transform>(std::make_shared<openvdb::math::AffineMap>(m)));
    CameraSettings cam = lookAtCamera(Vec3d(2e-5, 1e-5, 0.3), Vec3d(0.0), 64, 48);
    cam.near = 1e-7;
    cam.setFieldOfView(0.01);
    // Seen almost end-on the needle is 1000 voxel lengths deep: keep it optically thin, or the
    // low-pass filter's 1 pixel^2 widens an opaque silhouette by several pixels (the reference
    // is not band-limited), which is EWA working as designed, not an error.
    RenderSettings thin = absorberSettings(1e-4);
    expectMatchesReference(grid, cam, 0.03, thin, 1.0);
}

TEST(Extremes, SmallVoxelsFarFromTheOrigin)
{
    // Voxels of 1e-3 a million units from the origin, camera beside them: camera-relative
    // double precision keeps the image equal to the one at the origin.
    auto render = [](const Vec3d& offset, bool doublePrecision) {
        auto grid = cube(12, 0.3f, 1e-3);
        grid->transform().postTranslate(openvdb::Vec3d(offset.x, offset.y, offset.z));
        CameraSettings cam = lookAtCamera(offset + Vec3d(0.01, 0.02, 0.06), offset, 64, 48);
        cam.near = 1e-5;
        RenderSettings s;
        s.splat.doublePrecision = doublePrecision;
        return renderGrid(grid, cam, s);
    };
    const Image origin = render(Vec3d(0.0), true);
    const Image far = render(Vec3d(1e6, -1e6, 1e6), true);
    expectSane(far);
    EXPECT_GT(alphaSum(origin), 100.0);
    EXPECT_LT(rmse(origin, far), 1e-3);
    // --precision float: positions rounded to float 1e6 from the origin (ulp 0.06) lose the
    // 1e-3 voxels entirely; the image is wrong but still finite.
    const Image farFloat = render(Vec3d(1e6, -1e6, 1e6), false);
    expectSane(farFloat);
    const Image originFloat = render(Vec3d(0.0), false);
    std::printf("  1e6 offset: RMSE double %.2e, float %.2e; at the origin float vs double %.2e\n", rmse(origin, far),
        rmse(origin, farFloat), rmse(origin, originFloat));
    EXPECT_GT(rmse(origin, farFloat), 100.0 * std::max(rmse(origin, far), 1e-6));
    EXPECT_LT(rmse(origin, originFloat), 1e-3);
}

TEST(Extremes, Anisotropy1000To1)
{
    // Voxels 0.1 x 0.1 x 1e-4 (1000:1), tilted: a thin sheet seen at an angle.
    auto grid = cube(8, 1.0f, 1.0);
    openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
    m.setToScale(openvdb::Vec3d(0.1, 0.1, 1e-4));
    m.postRotate(openvdb::math::X_AXIS, 0.5);
    grid->setTransform(std::make_shared<openvdb::math::Transform>(std::make_shared<openvdb::math::AffineMap>(m)));
    CameraSettings cam = lookAtCamera(Vec3d(0.5, 0.8, 3.0), Vec3d(0.0), 64, 48);
    RenderSettings s;
    expectMatchesReference(grid, cam, 0.03, s, 0.02);
}

TEST(Extremes, ShearWithNearZeroDeterminant)
{
    // Index axes x and y map to nearly parallel world vectors: det A = 1e-3 h^3.
    const double h = 0.1;
    auto grid = cube(8, 2.0f, 1.0);
    openvdb::math::Mat4d m = openvdb::math::Mat4d::identity(); // row i: world image of index axis i
    m[0][0] = h;
    m[1][0] = h;
    m[1][1] = h * 1e-3;
    m[2][2] = h;
    grid->setTransform(std::make_shared<openvdb::math::Transform>(std::make_shared<openvdb::math::AffineMap>(m)));
    CameraSettings cam = lookAtCamera(Vec3d(0.3, 3.0, 0.4), Vec3d(0.0), 64, 48);
    cam.up = Vec3d(0, 0, -1);
    expectMatchesReference(grid, cam, 0.03, RenderSettings(), 0.02);
}

TEST(Extremes, LightDirectionOfAnyLength)
{
    // The light's direction is only a direction: 1e-300 or 1e300 long, it lights alike (its
    // square once overflowed or vanished in the normalisation and built a light map of NaNs).
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    CameraSettings cam;
    cam.width = 48;
    cam.height = 36;
    cam.translate = Vec3d(1.0, 0.5, 4.0);
    const Camera camera(cam, cloud.worldCentre());
    RenderSettings s;
    s.lights[0].direction = Vec3d(0.3, 0.3, 0.0);
    const Image unit = Renderer(s).render(cloud, camera);
    expectSane(unit);
    for (const double scale : {1e-300, 1e300}) {
        s.lights[0].direction = Vec3d(0.3, 0.3, 0.0) * scale;
        const Image img = Renderer(s).render(cloud, camera);
        EXPECT_EQ(img.rgba, unit.rgba) << "light direction x " << scale;
    }
}

TEST(Extremes, ShadowGainsOfEveryMagnitudeLightAsTheReferenceDoes)
{
    // vdb_render's weight 1 / (1 + gain s) at --gain 1e308: no shadow sample a step away or more
    // weighs, so the light reaches every point whole. The light map's sum of exponentials once
    // grew without end there (151 s and 22.9 GB on the sample cloud); now it is a few terms, and
    // the splatter stays as close to the reference's exact weight as at the default gain.
    const auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(
        openvdb::ConstPtrCast<openvdb::FloatGrid>(makeSampleGrid(SampleGrid::Cloud, 0.05).impl().grid)->deepCopyGrid());
    const CameraSettings cam = lookAtCamera(Vec3d(1.5, 0.8, 4.5), Vec3d(0.0), 48, 32);
    const auto render = [&](double gain, Method method) {
        RenderSettings s;
        s.shadow.gain = gain;
        s.method = method;
        s.step = 0.25;
        const Image img = renderGrid(grid, cam, s);
        expectSane(img);
        return img;
    };
    const auto redSum = [](const Image& img) {
        double sum = 0.0;
        for (std::size_t i = 0; i < img.rgba.size(); i += 4) sum += img.rgba[i];
        return sum;
    };
    const Image defaultSplat = render(0.2, Method::Splat), defaultRef = render(0.2, Method::RayMarch);
    const double defaultError = rmse(defaultSplat, defaultRef, 0);
    Image previous;
    for (const double gain : {1e30, 1e308, std::numeric_limits<double>::max()}) {
        SCOPED_TRACE(gain);
        const auto start = std::chrono::steady_clock::now();
        const Image splat = render(gain, Method::Splat);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        const Image ref = render(gain, Method::RayMarch);
        const double error = rmse(splat, ref, 0);
        std::printf("  gain %g: splat %.3f s, red RMSE against the reference %.2e (%.2e at the default gain), red %.1f (%.1f)\n", gain,
            seconds, error, defaultError, redSum(ref), redSum(defaultRef));
        EXPECT_LT(seconds, 20.0);
        EXPECT_LT(error, 1.25 * defaultError);
        EXPECT_GT(redSum(ref), 1.05 * redSum(defaultRef)) << "no shadow at all: more light than at the default gain";
        if (!previous.rgba.empty()) {
            EXPECT_LT(maxAbsDiff(splat, previous), 1e-4) << "the limit is reached by 1e30";
        }
        previous = splat;
    }
    // Denormal gains are no gain: 1/g overflowed in the fit, and it looped forever.
    const Image none = render(0.0, Method::Splat);
    for (const double gain : {1e-310, std::numeric_limits<double>::denorm_min()}) {
        const auto start = std::chrono::steady_clock::now();
        EXPECT_LT(maxAbsDiff(render(gain, Method::Splat), none), 1e-4) << gain; // the fit's 1e-4
        EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 20.0) << gain;
    }
}

TEST(Extremes, OnePixelAndHugeImages)
{
    const GridSource g = makeSampleGrid(SampleGrid::Cloud, 0.08);
    // One pixel looking into the cloud: the pixel is covered.
    CameraSettings one = lookAtCamera(Vec3d(0, 0, 2.5), Vec3d(0.0), 1, 1);
    one.setFieldOfView(10.0);
    const Image px = Renderer(RenderSettings()).render(g, Camera(one, g.worldCentre()));
    expectSane(px);
    EXPECT_GT(px.rgba[3], 0.5f);

    CameraSettings big = lookAtCamera(Vec3d(1.5, 0.8, 4.5), Vec3d(0.0), 8192, 8192);
    const Image huge = Renderer(RenderSettings()).render(g, Camera(big, g.worldCentre()));
    expectSane(huge);
    CameraSettings small = big;
    small.width = small.height = 1024;
    const Image ref = Renderer(RenderSettings()).render(g, Camera(small, g.worldCentre()));
    // Same framing: coverage scales with the pixel count.
    EXPECT_NEAR(alphaSum(huge) / 64.0, alphaSum(ref), 0.01 * alphaSum(ref));
}

TEST(Extremes, MemoryBudgetStopsEachStageBeforeItAllocates)
{
    // Each count is checked against RenderSettings::maxMemory before its arrays exist: the
    // frame's pixels, the kernels of voxels and active tiles (a damaged file's thousands of
    // 4096^3 tiles), and the splat-tile pairs of footprints that cover the image.
    const auto message = [](const std::function<void()>& render) {
        try {
            render();
        } catch (const BudgetError& e) {
            return std::string(e.what());
        }
        return std::string("no BudgetError");
    };
    RenderSettings s;
    s.maxMemory = 256.0 * 1024 * 1024;
    s.cull = false; // the whole frame's checks (the streamed frame's windows fit: StreamedFrame.*)
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.08);
    const std::string pixels = message([&] {
        Renderer(s).render(cloud, Camera(lookAtCamera(Vec3d(1.5, 0.8, 4.5), Vec3d(0.0), 4096, 4096), cloud.worldCentre()));
    });
    EXPECT_NE(pixels.find("16777216 pixels need 1.5 GB, over the memory budget of 256 MB (--max-memory)"), std::string::npos) << pixels;
    EXPECT_NE(pixels.find("grid 'density'"), std::string::npos) << pixels;

    auto tiles = openvdb::FloatGrid::create(0.0f);
    tiles->setName("density");
    for (int i = 0; i < 64; ++i) tiles->tree().addTile(3, openvdb::Coord(4096 * i, 0, 0), 1.0f, true); // 64 x 4096^3 voxels
    const GridSource tiled = gridSourceFromOpenVDB(tiles);
    // From inside the row, along it: the tiles near the eye keep lattices of 8 to 64 voxels
    // (seen from afar each would be a few kernels: TilesSeenSmall.*).
    const std::string kernels = message([&] {
        Renderer(s).render(tiled, Camera(lookAtCamera(Vec3d(131072.0 + 2048.0, 2048.0, 2048.0), Vec3d(1e6, 2048.0, 2048.0), 64, 64), tiled.worldCentre()));
    });
    EXPECT_NE(kernels.find("voxel and active-tile kernels need"), std::string::npos) << kernels;

    // 64^3 voxels (64 MB of kernels) of sigma 4 voxels, 15 pixels a voxel: each splat covers
    // about 500 of the 1024^2 image's 4096 tiles, 1.3e8 pairs in all.
    const GridSource box = gridSourceFromOpenVDB(cube(32, 0.01f, 0.1));
    RenderSettings wide = s;
    wide.splat.kernelSigma = 4.0;
    wide.splat.pixelSize = 1; // every pixel (at 4 x 4 blocks a 16th of the pairs fit)
    const std::string pairs = message([&] {
        Renderer(wide).render(box, Camera(lookAtCamera(Vec3d(0.0, 0.0, 11.0), Vec3d(0.0), 1024, 1024), box.worldCentre()));
    });
    EXPECT_NE(pairs.find("splat-tile pairs need"), std::string::npos) << pairs;

    // The surface rasteriser too, before it bins: a sphere's surface kernels (about 3e4 of them,
    // a few pixels wide) make tens of thousands of pairs, over a budget of 64 KB (16384 pairs).
    const GridSource sphere = gridSourceFromOpenVDB(sphereLevelSet(1.0, 0.02));
    const detail::SurfaceSet surfaces = detail::extractSurfaceKernels(sphere.impl(), detail::SurfaceRequest{});
    detail::SurfaceStats surfaceStats;
    const detail::MemoryBudget small(65536.0, "sphere");
    const std::string surfacePairs = message([&] {
        const Camera near(lookAtCamera(Vec3d(0.0, 0.0, 3.0), Vec3d(0.0), 512, 512), Vec3d(0.0));
        detail::rasterizeSurfaces(detail::projectSurfaceSplats(surfaces, near, s), near, s, {}, surfaceStats, nullptr, &small);
    });
    EXPECT_NE(surfacePairs.find("splat-tile pairs need"), std::string::npos) << surfacePairs;
}

// Eight active tiles of 128^3 voxels at the corners of a cube 2^14 voxels wide, seen from far
// away (each tile a fraction of a pixel): the slabs follow what the pixels resolve (a sixteenth
// of --lod pixel widths at the nearest tile, of --supersample-span at --lod 0) instead of --slab, and
// each tile is one kernel its own size; the image is that of thin slabs and the tiles' lattices
// seen large (--lod 1e-3) within a percent summed. The shared assets' images do not change
// (their voxels are wider).
TEST(Extremes, SlabsFollowWhatThePixelsResolveFarAway)
{
    openvdb::FloatGrid::Ptr tiles = openvdb::FloatGrid::create(0.0f);
    tiles->setGridClass(openvdb::GRID_FOG_VOLUME);
    for (int c = 0; c < 8; ++c) tiles->tree().addTile(2, openvdb::Coord(c & 1 ? 16384 : 0, c & 2 ? 16384 : 0, c & 4 ? 16384 : 0), 0.5f, true);
    const GridSource grid = gridSourceFromOpenVDB(tiles);
    const Camera far(lookAtCamera(Vec3d(8256.0, 8256.0, 60000.0), Vec3d(8256.0), 64, 48), grid.worldCentre());
    RenderSettings thick; // --lod 2
    // The frame's own pixels (tiles larger than a leaf ask for no sub-pixels; were they forced,
    // the slabs would follow the sub-pixels).
    thick.splat.supersample = 1;
    RenderSettings thin = thick;
    thin.splat.lodPixels = 1e-3; // slabs of --slab 2 voxels, tiles' lattices of --tile-spacing 4
    RenderSettings off = thick;
    off.splat.lodPixels = 0.0; // slabs no thinner than --supersample-span (2) / 16 pixels
    // The nearest active value: the tiles' far corner at z = 16,511 (padded half a voxel).
    const double pixel = (60000.0 - 16511.5) / far.focalPixels();
    EXPECT_NEAR(detail::frameSlabs(grid.impl(), far, thick).thickness, 2.0 / 16.0 * pixel, 1e-9 * pixel);
    EXPECT_EQ(detail::frameSlabs(grid.impl(), far, thin).thickness, 2.0);
    EXPECT_NEAR(detail::frameSlabs(grid.impl(), far, off).thickness, 2.0 / 16.0 * pixel, 1e-9 * pixel);
    const Camera near(lookAtCamera(Vec3d(64.0, 64.0, 400.0), Vec3d(64.0), 64, 48), grid.worldCentre());
    EXPECT_EQ(detail::frameSlabs(grid.impl(), near, thick).thickness, 2.0);
    RenderStats a, b;
    const Image withLod = Renderer(thick).render(grid, far, &a);
    const Image without = Renderer(thin).render(grid, far, &b);
    double rgb[2] = {0.0, 0.0}, alpha[2] = {0.0, 0.0}, peak = 0.0;
    for (std::size_t i = 0; i < without.rgba.size(); ++i) {
        (i % 4 == 3 ? alpha : rgb)[0] += withLod.rgba[i];
        (i % 4 == 3 ? alpha : rgb)[1] += without.rgba[i];
        peak = std::max(peak, double(without.rgba[i]));
    }
    std::printf("slab composites %llu against %llu; max difference %.3g (peak %.3g); RGB sum %.4g against %.4g, alpha sum %.4g against %.4g\n",
        (unsigned long long)a.slabComposites, (unsigned long long)b.slabComposites, maxAbsDiff(withLod, without), peak, rgb[0], rgb[1], alpha[0], alpha[1]);
    // Measured: 2,160 slab composites against 28,541; RGB summed 52.48 against 51.59, alpha
    // 28.11 against 28.15; the largest pixel difference 0.105 (of 0.58), where a tile's one
    // kernel is lit where its lattice's 32^3 were. With the lattices seen large both ways (before
    // they followed the pixels): 1,112 composites, RGB within 0.23 %, 0.016 at most.
    EXPECT_GT(alpha[1], 10.0);
    EXPECT_LT(a.slabComposites * 10, b.slabComposites);
    EXPECT_NEAR(rgb[0], rgb[1], 0.025 * rgb[1]);
    EXPECT_NEAR(alpha[0], alpha[1], 3e-3 * alpha[1]);
    EXPECT_LE(maxAbsDiff(withLod, without), 0.25 * peak);
}

TEST(Extremes, MemoryBudgetCountsKernelsAfterTheLevelOfDetailMergesThem)
{
    // A voxel costs a 32-byte kernel slot until the level of detail has merged its block; only
    // the kernels left pay the pipeline's 256 bytes. 320,200 voxels: 10 MB of slots, 82 MB as
    // unmerged kernels, over a 64 MB budget; from far away they merge into a few thousand.
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.02);
    const Camera far(lookAtCamera(Vec3d(3.0, 1.6, 9.0), Vec3d(0.0), 160, 90), cloud.worldCentre());
    RenderSettings merged;
    merged.maxMemory = 64.0 * 1024 * 1024;
    merged.splat.supersample = 1; // merged at the frame's pixels, not sub-pixels the voxels span
    RenderStats stats;
    const Image image = Renderer(merged).render(cloud, far, &stats);
    EXPECT_EQ(stats.activeVoxels, 320200u);
    EXPECT_LT(stats.kernels * 256, 64u * 1024 * 1024);
    EXPECT_GT(alphaSum(image), 50.0);
    RenderSettings unmerged = merged;
    unmerged.splat.lodPixels = 0.0;
    unmerged.cull = false; // the whole frame builds them all at once (the streamed frame a window at a time)
    try {
        Renderer(unmerged).render(cloud, far);
        ADD_FAILURE() << "no BudgetError";
    } catch (const BudgetError& e) {
        EXPECT_NE(std::string(e.what()).find("kernels need"), std::string::npos) << e.what();
    }
}
