/// @file surface_test.cpp
/// @brief Level sets rendered with flattened surface kernels (Sec. 6.3, 6.4, 7.2) against
///        analytic spheres, planes and tori, and against vdb_render's silhouettes.
#include "fixtures.h"

#include <gtest/gtest.h>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

openvdb::FloatGrid::Ptr torusLevelSet(double major, double minor, double h)
{
    const int n = int(std::ceil((major + minor) / h)) + 4, m = int(std::ceil(minor / h)) + 4;
    return makeLevelSet(
        [=](const Vec3d& p) { return std::hypot(std::hypot(p.x, p.z) - major, p.y) - minor; },
        openvdb::Coord(-n, -m, -n), openvdb::Coord(n, m, n), h);
}

RenderSettings shaded(SurfaceShader shader)
{
    RenderSettings s;
    s.surface.shader = shader;
    return s;
}

} // namespace

TEST(Surface, SphereHasTheRightRadiusAndNormals)
{
    // Orthographic, 3 world units over 150 pixels: the unit sphere's disc has radius 50 px.
    const GridSource sphere = gridSourceFromOpenVDB(sphereLevelSet(1.0, 0.04));
    const Camera camera(orthoDownZ(0.0, 0.0, 5.0, 3.0, 150), Vec3d(0.0));
    PassRequest depth;
    depth.depth = true;
    const Frame f = Renderer(shaded(SurfaceShader::Normal)).renderFrame(sphere, camera, depth);
    ASSERT_TRUE(f.beauty.allFinite());
    const double radiusPixels = std::sqrt(alphaSum(f.beauty) / 3.14159265358979);
    EXPECT_NEAR(radiusPixels, 50.0, 0.5);
    // Normal shader: colour = (N + 1) / 2 of the world normal, premultiplied by alpha = 1.
    for (const auto& [x, y] : {std::pair{75, 75}, {95, 70}, {60, 100}, {110, 80}, {75, 40}}) {
        const double wx = (x + 0.5 - 75.0) / 50.0, wy = -(y + 0.5 - 75.0) / 50.0; // raster y points down
        const Vec3d n(wx, wy, std::sqrt(1.0 - wx * wx - wy * wy));
        const float* px = f.beauty.pixel(x, y);
        EXPECT_NEAR(px[3], 1.0, 1e-3) << x << "," << y;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(px[c], 0.5 * (n[c] + 1.0), 0.02) << x << "," << y << " channel " << c;
        // Z: the camera depth of the sphere's front, 5 - n_z.
        EXPECT_NEAR(f.depth[std::size_t(y) * 150 + std::size_t(x)], 5.0 - n.z, 0.02) << x << "," << y;
    }
    EXPECT_TRUE(std::isinf(f.depth[0])) << "background";
    RenderSettings fogOption = shaded(SurfaceShader::Normal);
    fogOption.surface.iso = 0.5;
    EXPECT_THROW(Renderer(fogOption).render(sphere, camera), ValueError) << "--iso is for fog volumes";
}

TEST(Surface, GrazingPlaneHasNoHolesAndNoNaN)
{
    // A plane y = 0 seen from 5 degrees above it: every pixel well inside its image is covered.
    const double h = 0.05;
    const GridSource plane = gridSourceFromOpenVDB(
        makeLevelSet([](const Vec3d& p) { return p.y; }, openvdb::Coord(-80, -5, -80), openvdb::Coord(80, 5, 80), h));
    for (const double degrees : {5.0, 30.0, 89.0}) {
        CameraSettings c;
        c.width = 160;
        c.height = 120;
        const double a = degrees * 3.14159265358979 / 180.0;
        c.translate = Vec3d(0.0, 2.0 * std::sin(a), 2.0 * std::cos(a));
        c.lookAt = Vec3d(0.0);
        c.setFieldOfView(40.0);
        const Image img = Renderer(shaded(SurfaceShader::Matte)).render(plane, Camera(c, Vec3d(0.0)));
        ASSERT_TRUE(img.allFinite()) << degrees;
        // The centre rows see the plane near the look-at point, well inside its 8 x 8 extent.
        int holes = 0;
        for (int y = 55; y < 65; ++y)
            for (int x = 20; x < 140; ++x) holes += img.pixel(x, y)[3] < 0.99f;
        EXPECT_EQ(holes, 0) << degrees << " degrees";
    }
}

TEST(Surface, ShadersFollowVdbRender)
{
    const GridSource sphere = gridSourceFromOpenVDB(sphereLevelSet(1.0, 0.04));
    const Camera camera(orthoDownZ(0.0, 0.0, 5.0, 3.0, 150), Vec3d(0.0));
    const Image matte = Renderer(shaded(SurfaceShader::Matte)).render(sphere, camera);
    const Image diffuse = Renderer(shaded(SurfaceShader::Diffuse)).render(sphere, camera);
    const Image position = Renderer(shaded(SurfaceShader::Position)).render(sphere, camera);
    EXPECT_NEAR(matte.pixel(75, 75)[0], 1.0, 1e-3);
    // Diffuse: |N . ray| = N_z for an orthographic camera looking down -z.
    const double wx = (100.5 - 75.0) / 50.0;
    EXPECT_NEAR(diffuse.pixel(100, 75)[1], std::sqrt(1.0 - wx * wx), 0.02);
    // Position: (P - min) / size over the active voxels' box (about +-1.12 with the band).
    EXPECT_NEAR(position.pixel(75, 75)[0], 0.5, 0.02);
    EXPECT_GT(position.pixel(75, 75)[2], 0.85);
}

TEST(Surface, SilhouettesMatchVdbRender)
{
    const std::string vdbRender = vdbRenderPath();
    if (vdbRender.empty()) GTEST_SKIP() << "vdb_render is not installed";
    TempDir dir;
    struct Case
    {
        std::string name, path, camera;
    };
    std::vector<Case> cases;
    writeGrid(sphereLevelSet(1.0, 0.03), dir.file("sphere.vdb"));
    writeGrid(torusLevelSet(1.0, 0.35, 0.03), dir.file("torus.vdb"));
    cases.push_back({"sphere", dir.file("sphere.vdb"), "-translate 0.3,0.5,4 -lookat 0,0,0"});
    cases.push_back({"torus", dir.file("torus.vdb"), "-translate 0,2.5,3 -lookat 0,0,0"});
    const std::string assets = assetsDir();
    if (!assets.empty()) {
        cases.push_back({"cube", assets + "/cube_levelset.vdb", "-translate 10,12,18 -lookat 0,0,0"});
        cases.push_back({"bunny", assets + "/bunny_levelset.vdb", "-translate 0,0,4.859 -lookat 0,0,0"});
    }
    for (const Case& c : cases) {
        const std::string ours = dir.file(c.name + "_ewa.exr"), theirs = dir.file(c.name + "_vr.exr");
        const std::string args = " -res 320x240 -shader matte " + c.camera;
        ASSERT_EQ(std::system((std::string(VDB_EWA_CLI_PATH) + " render " + c.path + " " + ours + args + " --exr-type float").c_str()), 0) << c.name;
        if (std::getenv("VDB_EWA_KEEP")) std::filesystem::copy_file(ours, std::string(std::getenv("VDB_EWA_KEEP")) + "/" + c.name + "_ewa.exr", std::filesystem::copy_options::overwrite_existing);
        ASSERT_EQ(std::system((vdbRender + " " + c.path + " " + theirs + args).c_str()), 0) << c.name;
        if (std::getenv("VDB_EWA_KEEP")) std::filesystem::copy_file(theirs, std::string(std::getenv("VDB_EWA_KEEP")) + "/" + c.name + "_vr.exr", std::filesystem::copy_options::overwrite_existing);
        // vdb_render writes alpha 1 everywhere for level sets: its mask is the matte colour.
        Image mask = readExr(theirs);
        for (std::size_t i = 0; i < mask.rgba.size(); i += 4) mask.rgba[i + 3] = mask.rgba[i];
        const double iou = alphaMaskIoU(readExr(ours), mask, 0.5f);
        EXPECT_GE(iou, 0.99) << c.name;

        // Normal shader away from silhouettes: pixels whose 5x5 neighbourhood is covered in both.
        const std::string oursN = dir.file(c.name + "_ewa_n.exr"), theirsN = dir.file(c.name + "_vr_n.exr");
        const std::string argsN = " -res 320x240 -shader normal " + c.camera;
        ASSERT_EQ(std::system((std::string(VDB_EWA_CLI_PATH) + " render " + c.path + " " + oursN + argsN + " --exr-type float").c_str()), 0);
        ASSERT_EQ(std::system((vdbRender + " " + c.path + " " + theirsN + argsN).c_str()), 0);
        const Image a = readExr(oursN), b = readExr(theirsN), ma = readExr(ours);
        std::vector<double> errors;
        for (int y = 2; y < 238; ++y)
            for (int x = 2; x < 318; ++x) {
                bool inside = true;
                for (int dy = -2; dy <= 2 && inside; ++dy)
                    for (int dx = -2; dx <= 2 && inside; ++dx) {
                        inside = ma.pixel(x + dx, y + dy)[3] > 0.999f && mask.pixel(x + dx, y + dy)[3] > 0.5f;
                    }
                if (!inside) continue;
                for (int ch = 0; ch < 3; ++ch) errors.push_back(std::abs(a.pixel(x, y)[ch] - b.pixel(x, y)[ch]));
            }
        ASSERT_GT(errors.size(), 1000u) << c.name;
        std::sort(errors.begin(), errors.end());
        const double median = errors[errors.size() / 2], p95 = errors[errors.size() * 95 / 100];
        std::printf("%s: silhouette IoU %.4f; normal shader |difference| median %.4f, 95th percentile %.4f\n",
            c.name.c_str(), iou, median, p95);
        EXPECT_LT(median, 0.02) << c.name;
        EXPECT_LT(p95, 0.08) << c.name;
    }
}

namespace {

/// The paper's Fig. 15 scene: a plane y = 0 with a checker colour grid (squares of 2 voxels,
/// h = 0.05), seen from 0.5 units above it; towards the horizon the squares shrink far below
/// a pixel.
struct CheckerPlane
{
    static constexpr double h = 0.05;
    static constexpr int kLo = -400, kHi = 40, iHalf = 160;

    static openvdb::Vec3SGrid::Ptr colors(const openvdb::math::Transform& xform)
    {
        auto checker = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
        checker->setTransform(xform.copy());
        checker->setName("checker");
        auto acc = checker->getAccessor();
        for (int i = -iHalf; i <= iHalf; ++i)
            for (int j = -3; j <= 3; ++j)
                for (int k = kLo; k <= kHi; ++k) acc.setValueOn(openvdb::Coord(i, j, k), openvdb::Vec3s(float(((i >> 1) + (k >> 1)) & 1)));
        return checker;
    }

    /// As a level set (surface kernels).
    static GridSource surface()
    {
        auto plane = makeLevelSet([](const Vec3d& p) { return p.y; }, openvdb::Coord(-iHalf, -4, kLo), openvdb::Coord(iHalf, 4, kHi), h);
        return withColorGrid(gridSourceFromOpenVDB(plane), colors(plane->transform()));
    }

    /// As a fog sheet two voxels thick, y in [-h, 0] (volume kernels), optical depth 3 per voxel
    /// length at extinction 1: opaque at the angles the camera sees it.
    static GridSource volume()
    {
        auto sheet = makeBoxGrid(openvdb::Coord(-iHalf, -1, kLo), openvdb::Coord(iHalf, 0, kHi), 3.0f, h);
        return withColorGrid(gridSourceFromOpenVDB(sheet), colors(sheet->transform()));
    }

    static Camera camera()
    {
        CameraSettings c;
        c.width = 320;
        c.height = 240;
        c.translate = Vec3d(0.0, 0.5, 2.0);
        c.lookAt = Vec3d(0.0, 0.0, -6.0);
        return Camera(c, Vec3d(0.0));
    }

    /// Mean and standard deviation of colour / alpha over the opaque pixels of rows [y0, y1).
    /// Mean and std. deviation of the un-premultiplied red of the opaque pixels (alpha >= @a opaque).
    static std::pair<double, double> rowStats(const Image& img, int y0, int y1, float opaque = 0.99f)
    {
        double s = 0, s2 = 0;
        int n = 0;
        for (int y = y0; y < y1; ++y)
            for (int x = 40; x < 280; ++x) {
                const float* p = img.pixel(x, y);
                if (p[3] < opaque) continue;
                const double v = p[0] / p[3];
                s += v;
                s2 += v * v;
                ++n;
            }
        const double mean = s / n;
        return {mean, std::sqrt(std::max(0.0, s2 / n - mean * mean))};
    }

    /// The first row from the top that is covered.
    /// The first row (from the top) whose centre pixel is opaque: alpha >= @a opaque.
    static int horizon(const Image& img, float opaque = 0.99f)
    {
        int y = 0;
        while (y < img.height && img.pixel(160, y)[3] < opaque) ++y;
        return y;
    }
};

} // namespace

TEST(Surface, CheckerPlaneAtAGrazingAngleShowsNoMoire)
{
    // The EWA filter (Eq. 35 plus the low-pass) averages the far squares to the mean grey;
    // point-sampled footprints (--aa none) alias into moire. Texture contrast must survive
    // where the squares are resolvable.
    const GridSource source = CheckerPlane::surface();
    const Camera camera = CheckerPlane::camera();
    RenderSettings ewa = shaded(SurfaceShader::Matte), point = ewa;
    point.splat.antiAliasing = AntiAliasing::None;
    const Image filtered = Renderer(ewa).render(source, camera), aliased = Renderer(point).render(source, camera);
    ASSERT_TRUE(filtered.allFinite());
    // Rows by the distance they see: the plane at depth d is at row y = cy + f * 0.5 / d (about).
    const int horizon = CheckerPlane::horizon(filtered);
    ASSERT_LT(horizon, 200);
    const auto [farMean, farSd] = CheckerPlane::rowStats(filtered, horizon + 2, horizon + 12);
    const auto [aliasMean, aliasSd] = CheckerPlane::rowStats(aliased, horizon + 2, horizon + 12);
    const auto [nearMean, nearSd] = CheckerPlane::rowStats(filtered, 200, 240);
    std::printf("checker: far rows EWA mean %.3f sd %.3f, --aa none sd %.3f; near rows EWA sd %.3f\n", farMean, farSd,
        aliasSd, nearSd);
    EXPECT_NEAR(farMean, 0.5, 0.05);
    EXPECT_LT(farSd, 0.06) << "far rows converge to the mean grey";
    EXPECT_GT(aliasSd, 2.0 * farSd) << "point sampling aliases (the test can tell)";
    EXPECT_GT(nearSd, 0.15) << "the checker is still resolved near the camera";
    if (const char* keep = std::getenv("VDB_EWA_KEEP")) {
        writeExr(filtered, std::string(keep) + "/checker_ewa.exr");
        writeExr(aliased, std::string(keep) + "/checker_none.exr");
    }
}

TEST(Surface, CheckerSheetWithVolumeKernelsFiltersButBlursTheTexture)
{
    // The paper's Fig. 15 comparison: the same texture on a fog sheet two voxels thick,
    // rendered with volume kernels (colour grid x scattering albedo). EWA volume splats also
    // converge to the mean far away, but a kernel's depth extent smears it across the screen at
    // a grazing angle: near the camera the surface kernels keep more contrast.
    const Camera camera = CheckerPlane::camera();
    RenderSettings volume;
    volume.lights[0].direction = Vec3d(0, 1, 0);
    volume.lights[0].color = Vec3d(1.0);
    volume.medium.absorb = Vec3d(0.0);
    volume.medium.scatter = Vec3d(1.0);
    volume.shadow.step = 0.25;
    const Image sheet = Renderer(volume).render(CheckerPlane::volume(), camera);
    const Image plane = Renderer(shaded(SurfaceShader::Matte)).render(CheckerPlane::surface(), camera);
    ASSERT_TRUE(sheet.allFinite());
    // A fog volume's opaque pixels keep vdb_render's residual transmittance sqrt(cutoff / 3)
    // (alpha 0.959 at the default cutoff), where rays stop.
    const int horizon = CheckerPlane::horizon(sheet, 0.95f);
    ASSERT_LT(horizon, 200);
    const auto [farMean, farSd] = CheckerPlane::rowStats(sheet, horizon + 2, horizon + 12, 0.95f);
    const auto [nearMean, nearSd] = CheckerPlane::rowStats(sheet, 200, 240, 0.95f);
    const auto [surfaceNearMean, surfaceNearSd] = CheckerPlane::rowStats(plane, 200, 240);
    std::printf("checker sheet, volume kernels: far rows mean %.3f sd %.3f; near rows mean %.3f sd %.3f "
                "(surface kernels: mean %.3f sd %.3f)\n",
        farMean, farSd, nearMean, nearSd, surfaceNearMean, surfaceNearSd);
    EXPECT_LT(farSd, 0.12 * farMean) << "far rows converge to the mean";
    EXPECT_GT(nearSd, 0.08 * nearMean) << "the checker is still visible near the camera";
    EXPECT_LT(nearSd / nearMean, surfaceNearSd / surfaceNearMean) << "volume kernels blur more than surface kernels";
    if (const char* keep = std::getenv("VDB_EWA_KEEP")) writeExr(sheet, std::string(keep) + "/checker_volume.exr");
}

TEST(Surface, ExtremesGiveFiniteImages)
{
    // NaN values in the band, the camera inside the sphere, on its surface, a one-voxel level
    // set, voxels of 2e-5 and 1e4: finite images, no crash.
    auto sphere = sphereLevelSet(1.0, 0.05);
    sphere->tree().setValueOn(openvdb::Coord(20, 0, 0), std::numeric_limits<float>::quiet_NaN());
    const GridSource withNaN = gridSourceFromOpenVDB(sphere);
    CameraSettings c;
    c.width = 64;
    c.height = 48;
    for (const Vec3d& eye : {Vec3d(0.0, 0.0, 4.0), Vec3d(0.0), Vec3d(0.0, 0.0, 1.0), Vec3d(0.0, 0.0, 1.0001)}) {
        c.translate = eye;
        c.lookAt = eye + Vec3d(0.3, 0.1, -1.0);
        const Image img = Renderer(RenderSettings{}).render(withNaN, Camera(c, Vec3d(0.0)));
        EXPECT_TRUE(img.allFinite()) << eye.z;
    }
    auto single = openvdb::FloatGrid::create(1.0f);
    single->setGridClass(openvdb::GRID_LEVEL_SET);
    single->tree().setValueOn(openvdb::Coord(0), -0.5f);
    c.translate = Vec3d(0.0, 0.0, 5.0);
    c.lookAt = Vec3d(0.0);
    EXPECT_TRUE(Renderer(RenderSettings{}).render(gridSourceFromOpenVDB(single), Camera(c, Vec3d(0.0))).allFinite());
    for (const double h : {2e-5, 1e4}) { // OpenVDB refuses maps with abs(det) < 3e-15
        auto s = sphereLevelSet(20.0 * h, h);
        c.translate = Vec3d(0.0, 0.0, 80.0 * h);
        c.near = 1e-3 * h;
        const Image img = Renderer(RenderSettings{}).render(gridSourceFromOpenVDB(s), Camera(c, Vec3d(0.0)));
        EXPECT_TRUE(img.allFinite()) << h;
        EXPECT_GT(alphaSum(img), 50.0) << h;
    }
}

TEST(Surface, IsoSurfaceInsideAFogVolumeIsOccludingAndTinted)
{
    // A fog ball (density 1, radius 1) with --iso 0.5, lit from +x; in front of it (towards the
    // camera on +z) a plate of density 0.4 (below the iso-value: it stays volume) with coloured
    // extinction, which the light's shadow rays do not cross; behind it an emitting blob. The
    // surface must hide the blob, and through the plate its colour must be the plate's
    // per-channel transmittance times its colour alone, plus the plate's own glow.
    const double h = 0.05;
    auto makeScene = [&](bool plate, bool blob) {
        auto g = openvdb::FloatGrid::create(0.0f);
        g->setTransform(openvdb::math::Transform::createLinearTransform(h));
        g->setName("density");
        auto acc = g->getAccessor();
        for (int i = -22; i <= 22; ++i)
            for (int j = -22; j <= 22; ++j)
                for (int k = -22; k <= 22; ++k) {
                    if (glm::length(Vec3d(i, j, k) * h) <= 1.0) acc.setValueOn(openvdb::Coord(i, j, k), 1.0f);
                }
        if (plate) {
            for (int i = -30; i <= 30; ++i)
                for (int j = -30; j <= 30; ++j)
                    for (int k = 30; k <= 33; ++k) acc.setValueOn(openvdb::Coord(i, j, k), 0.4f); // below --iso
        }
        if (blob) {
            for (int i = -6; i <= 6; ++i)
                for (int j = -6; j <= 6; ++j)
                    for (int k = -40; k <= -30; ++k) acc.setValueOn(openvdb::Coord(i, j, k), 1.0f);
        }
        return gridSourceFromOpenVDB(g);
    };
    const Camera camera(orthoDownZ(0.0, 0.0, 5.0, 3.0, 90), Vec3d(0.0));
    RenderSettings s;
    s.medium.absorb = Vec3d(0.3, 0.1, 0.02); // the plate's tint (scatter 0: a pure absorber)
    s.medium.scatter = Vec3d(0.0);
    s.medium.emission = Vec3d(0.5, 0.5, 0.5); // makes the blob (and the ball's inside) glow
    s.lights[0].direction = Vec3d(1.0, 0.0, 0.0);
    s.lights[0].color = Vec3d(1.0);
    s.cutoff = 0.0;
    s.surface.iso = 0.5;
    const int x = 60, y = 45; // surface point (0.5, 0, 0.87): lit at 60 degrees
    const Image alone = Renderer(s).render(makeScene(false, false), camera);
    const Image withBlob = Renderer(s).render(makeScene(false, true), camera);
    const Image withPlate = Renderer(s).render(makeScene(true, false), camera);
    EXPECT_NEAR(alone.pixel(x, y)[3], 1.0, 1e-3) << "the surface is opaque";
    EXPECT_GT(alone.pixel(x, y)[0], 0.05f) << "and lit";
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(withBlob.pixel(45, 45)[c], alone.pixel(45, 45)[c], 1e-4) << "the blob is hidden";
    // The plate alone: its per-channel transmittance (the transmittance pass) and its own glow.
    RenderSettings plateOnly = s;
    plateOnly.surface.iso = std::numeric_limits<double>::quiet_NaN();
    auto plateGrid = openvdb::FloatGrid::create(0.0f);
    plateGrid->setTransform(openvdb::math::Transform::createLinearTransform(h));
    {
        auto acc = plateGrid->getAccessor();
        for (int i = -30; i <= 30; ++i)
            for (int j = -30; j <= 30; ++j)
                for (int k = 30; k <= 33; ++k) acc.setValueOn(openvdb::Coord(i, j, k), 0.4f);
    }
    PassRequest transmittance;
    transmittance.transmittance = true;
    const Frame plate = Renderer(plateOnly).renderFrame(gridSourceFromOpenVDB(plateGrid), camera, transmittance);
    const std::size_t i = std::size_t(y) * 90 + std::size_t(x);
    for (int c = 0; c < 3; ++c) {
        const double expected = plate.transmittance[3 * i + c] * alone.pixel(x, y)[c] + plate.beauty.pixel(x, y)[c];
        EXPECT_NEAR(withPlate.pixel(x, y)[c], expected, 0.02 * expected + 1e-4) << "channel " << c;
    }
    EXPECT_LT(plate.transmittance[3 * i], 0.8 * plate.transmittance[3 * i + 2]) << "the plate tints: red is absorbed most";
}

// --shader and --isovalue shade and pick a level set's surface: on a fog volume (with or
// without --iso) they change nothing, and the render says so instead of ignoring them.
TEST(Surface, LevelSetOptionsOnAFogVolumeWarn)
{
    auto fog = makeBoxGrid(openvdb::Coord(0), openvdb::Coord(3), 1.0f, 0.1);
    auto sphere = makeBoxGrid(openvdb::Coord(-2), openvdb::Coord(2), -0.1f, 0.1);
    sphere->setGridClass(openvdb::GRID_LEVEL_SET);
    CameraSettings cam;
    cam.width = cam.height = 16;
    cam.translate = Vec3d(0.0, 0.0, 3.0);
    auto warned = [&](openvdb::FloatGrid::Ptr grid, const RenderSettings& s, const std::string& option) {
        RenderStats stats;
        renderGrid(grid, cam, s, &stats);
        for (const std::string& w : stats.warnings) {
            if (w.rfind(option + " changes nothing here", 0) == 0) return true;
        }
        return false;
    };
    RenderSettings s;
    EXPECT_FALSE(warned(fog, s, "--shader"));
    EXPECT_FALSE(warned(fog, s, "--isovalue"));
    s.surface.shader = SurfaceShader::Normal;
    EXPECT_TRUE(warned(fog, s, "--shader"));
    EXPECT_FALSE(warned(sphere, s, "--shader"));
    s.surface.iso = 0.5;
    EXPECT_TRUE(warned(fog, s, "--shader")); // the --iso surface is lit, not shaded
    s = RenderSettings();
    s.surface.isovalue = 0.05;
    EXPECT_TRUE(warned(fog, s, "--isovalue"));
    EXPECT_FALSE(warned(sphere, s, "--isovalue"));
}
