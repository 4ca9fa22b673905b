/// @file supersampling_test.cpp
/// @brief Sub-pixel samples (docs/equations.md#sub-pixel-samples): a camera averages
///        transmittance over a pixel, so what a volume of voxels smaller than a pixel covers is
///        the integral of 1 - exp(-tau) over the image plane, whatever the pixels. Checked
///        against that integral, computed numerically from the trilinear field, and against
///        the reference integrator at a scale where both converge.
#include "fixtures.h"
#include "supersampling.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

/// Columns of @a depth voxels along z (index = world, voxels 1 wide), of density
/// @a density x @a pattern(i, j) (0 or 1) over [0, n)^2.
openvdb::FloatGrid::Ptr columns(int n, int depth, float density, const std::function<bool(int, int)>& pattern)
{
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    grid->setName("density");
    auto acc = grid->getAccessor();
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            if (pattern(i, j))
                for (int k = 0; k < depth; ++k) acc.setValueOn(openvdb::Coord(i, j, k), density);
    return grid;
}

/// The closed form of what those columns cover, in world units^2: the trilinear field of a
/// column of `depth` voxels integrates to `depth` along z, so a ray at (x, y) crosses
/// tau(x, y) = sigma density depth B(x, y), B the bilinear interpolant of the pattern between
/// voxel centres; the integral of 1 - exp(-tau) by the midpoint rule, 16 x 16 points a voxel.
double coveredArea(int n, double tau, const std::function<bool(int, int)>& pattern)
{
    const auto v = [&](int i, int j) { return i >= 0 && j >= 0 && i < n && j < n && pattern(i, j) ? 1.0 : 0.0; };
    constexpr int kPoints = 16;
    double area = 0.0;
    for (int a = -kPoints; a < (n + 1) * kPoints; ++a) {
        const double x = (a + 0.5) / kPoints, fx = x - std::floor(x);
        const int i = int(std::floor(x));
        for (int b = -kPoints; b < (n + 1) * kPoints; ++b) {
            const double y = (b + 0.5) / kPoints, fy = y - std::floor(y);
            const int j = int(std::floor(y));
            const double bilinear = (1 - fx) * (1 - fy) * v(i, j) + fx * (1 - fy) * v(i + 1, j) + (1 - fx) * fy * v(i, j + 1) + fx * fy * v(i + 1, j + 1);
            area += 1.0 - std::exp(-tau * bilinear);
        }
    }
    return area / double(kPoints * kPoints);
}

/// Sum of alpha over @a image divided by @a pixelsPerUnit^2: world units^2 covered.
double coverage(const Image& image, double pixelsPerUnit)
{
    return alphaSum(image) / (pixelsPerUnit * pixelsPerUnit);
}

/// Sum of R + G + B over @a image divided by @a pixelsPerUnit^2: the light over the image
/// plane, in world units^2, the same whatever the pixels (orthographic).
double flux(const Image& image, double pixelsPerUnit)
{
    double s = 0.0;
    for (std::size_t i = 0; i < image.rgba.size(); ++i) {
        if (i % 4 != 3) s += image.rgba[i];
    }
    return s / (pixelsPerUnit * pixelsPerUnit);
}

/// A grey absorber of @a sigma per voxel length.
RenderSettings absorber(double sigma, int supersample)
{
    RenderSettings s = absorberSettings(sigma);
    s.splat.supersample = supersample;
    return s;
}

} // namespace

// A dense box 12 voxels wide (tau 8 through it) seen orthographically at a quarter of a pixel
// a voxel: 3 pixels wide, with its edges across pixels. Splatting optical depth filtered a pixel
// wide covers far more (filtered depth saturates beyond the edge, and 1 - exp(-tau) is
// concave: its filtered value exceeds the filtered coverage, Jensen); sub-pixels the voxels
// span cover what the camera's average does. At 20 pixels a voxel both agree.
TEST(Supersampling, AThickBoxSeenSmallCoversItsAreaAsTheCameraAverages)
{
    const auto box = [](int, int) { return true; };
    const int n = 12, depth = 12;
    const double sigma = 8.0 / depth;
    const double truth = coveredArea(n, sigma * depth, box);
    // The 11 x 11 core between voxel centres, 4 skirts of 11 where tau ramps from 0 to 8 over a
    // voxel, 4 corners of at most 1 each.
    const double sides = 121.0 * (1.0 - std::exp(-8.0)) + 44.0 * (1.0 - (1.0 - std::exp(-8.0)) / 8.0);
    EXPECT_GT(truth, sides);
    EXPECT_LT(truth, sides + 4.0);
    const auto grid = columns(n, depth, 1.0f, box);
    // Large: 20 pixels a voxel (frame 16 units over 320 pixels), no sub-pixels needed.
    const Image large = renderGrid(grid, orthoDownZ(6.0, 6.0, 100.0, 16.0, 320), absorber(sigma, 32));
    // The Gaussian sum's dense faces sit 0.08 voxels further out than the trilinear field's
    // (docs/numerics.md#dense-faces): 2.5 % of this box's area.
    const double faces = coverage(large, 20.0) / truth;
    EXPECT_NEAR(faces, 1.025, 0.01);
    // Small: a quarter of a pixel a voxel (frame 64 units over 16 pixels).
    RenderStats stats;
    const Image small = renderGrid(grid, orthoDownZ(6.0, 6.0, 100.0, 64.0, 16), absorber(sigma, 32), &stats);
    EXPECT_EQ(stats.supersample, 8); // ceil(2 / 0.25)
    EXPECT_NEAR(coverage(small, 0.25) / truth, faces, 0.02);
    const Image filtered = renderGrid(grid, orthoDownZ(6.0, 6.0, 100.0, 64.0, 16), absorber(sigma, 1));
    EXPECT_GT(coverage(filtered, 0.25) / truth, 1.5); // optical depth filtered a pixel wide
    std::printf("a thick box at 0.25 pixels a voxel covers %.3f of its area with sub-pixels, %.3f without (%.3f at 20 pixels a voxel)\n",
        coverage(small, 0.25) / truth, coverage(filtered, 0.25) / truth, faces);
}

// A checkerboard of opaque and clear columns 8 voxels square, each cell 0.4 pixels: a camera
// sees about half of every pixel opaque, a footprint a pixel wide a uniform half-density medium
// of optical depth 3, nearly opaque (0.95). Seen small, it covers what it covers seen at 4
// pixels a voxel, where the Gaussian sum's dense faces lie a little outside the trilinear
// field's.
TEST(Supersampling, ASubPixelCheckerboardOfOpaqueColumnsCoversHalf)
{
    const auto checker = [](int i, int j) { return ((i / 8) + (j / 8)) % 2 == 0; };
    const int n = 64, depth = 16;
    const double sigma = 6.0 / depth;
    const double truth = coveredArea(n, sigma * depth, checker);
    EXPECT_NEAR(truth / (n * n), 0.58, 0.02); // half, and the trilinear skirts of the opaque cells
    const auto grid = columns(n, depth, 1.0f, checker);
    const double faces = coverage(renderGrid(grid, orthoDownZ(32.0, 32.0, 100.0, 72.0, 288), absorber(sigma, 64)), 4.0) / truth;
    EXPECT_NEAR(faces, 1.0, 0.08);
    // 0.05 pixels a voxel: 64 voxels are 3.2 pixels (frame 320 units over 16 pixels).
    const CameraSettings camera = orthoDownZ(32.0, 32.0, 100.0, 320.0, 16);
    const double px = 16.0 / 320.0;
    RenderStats stats;
    const Image small = renderGrid(grid, camera, absorber(sigma, 64), &stats);
    EXPECT_EQ(stats.supersample, 40); // ceil(2 / 0.05)
    EXPECT_NEAR(coverage(small, px) / truth, faces, 0.03);
    const Image filtered = renderGrid(grid, camera, absorber(sigma, 1));
    EXPECT_GT(coverage(filtered, px) / truth, 1.3);
    std::printf("a checkerboard at 0.05 pixels a voxel covers %.3f of its area with sub-pixels, %.3f without (%.3f at 4 pixels a voxel)\n",
        coverage(small, px) / truth, coverage(filtered, px) / truth, faces);
}

// A thick, side-lit sphere with physical shadows: its light over the image plane is the same
// seen small (a quarter of a pixel a voxel, the sphere 5 pixels across) as the reference
// integrator's at 4 pixels a voxel. Filtered optical depth spreads the lit limb's light and
// makes the disc opaque beyond it.
TEST(Supersampling, ALitThickSphereSeenSmallKeepsItsLight)
{
    const double radius = 8.0;
    const auto grid = makeFogAround([&](const Vec3d& p) { return glm::length(p) - radius; }, 1.0, 12, 1.0);
    RenderSettings s;
    s.medium.scatter = Vec3d(2.0);
    s.medium.absorb = Vec3d(0.1);
    s.lights[0].direction = Vec3d(1.0, 0.0, 0.3);
    s.shadow.gain = 0.0;
    s.shadow.step = 0.25;
    s.step = 0.25;
    RenderSettings reference = s;
    reference.method = Method::RayMarch;
    const double truth = flux(renderGrid(grid, orthoDownZ(0.0, 0.0, 100.0, 28.0, 112), reference), 4.0);
    ASSERT_GT(truth, 50.0);
    // Seen small: 0.25 pixels a voxel.
    const CameraSettings small = orthoDownZ(0.0, 0.0, 100.0, 64.0, 16);
    EXPECT_NEAR(flux(renderGrid(grid, small, s), 0.25) / truth, 1.0, 0.03);
    RenderSettings filtered = s;
    filtered.splat.supersample = 1;
    EXPECT_GT(flux(renderGrid(grid, small, filtered), 0.25) / truth, 1.2);
    std::printf("a lit thick sphere at 0.25 pixels a voxel: light %.3f of the reference's with sub-pixels, %.3f without\n",
        flux(renderGrid(grid, small, s), 0.25) / truth, flux(renderGrid(grid, small, filtered), 0.25) / truth);
    // The reference seen small, 64 rays a pixel: the same light (its rays sample the pixel).
    reference.pixelSamples = 64;
    EXPECT_NEAR(flux(renderGrid(grid, small, reference), 0.25) / truth, 1.0, 0.02);
}

// The reference's rays spread over the pixel: a pixel half covered by an opaque box is half
// opaque with 64 rays, and all or nothing with its centre ray.
TEST(Supersampling, TheReferencesPixelSamplesAverageThePixel)
{
    const auto grid = columns(16, 16, 1.0f, [](int, int) { return true; });
    RenderSettings s = absorber(1.0, 1);
    s.method = Method::RayMarch;
    s.step = 0.25;
    // 0.5 pixels a voxel (frame 32 over 16 pixels, centred on x = 0): pixel 7 spans x in
    // [-2, 0]; its left half is clear, its right half the trilinear field's edge, rising from 0
    // at x = -1 to the box's value at x = 0, and its centre ray (x = -1) misses the box.
    const CameraSettings camera = orthoDownZ(0.0, 7.5, 100.0, 32.0, 16);
    const Image centre = renderGrid(grid, camera, s);
    s.pixelSamples = 64;
    const Image spread = renderGrid(grid, camera, s);
    const float centreAlpha = centre.pixel(7, 8)[3], spreadAlpha = spread.pixel(7, 8)[3];
    // The exact pixel average: x in [-1, 0] has tau = 16 (x + 1), the mean of 1 - exp(-tau)
    // over it 1 - (1 - e^-16) / 16, over half the pixel.
    const double exact = 0.5 * (1.0 - (1.0 - std::exp(-16.0)) / 16.0);
    EXPECT_NEAR(spreadAlpha, exact, 0.04);
    EXPECT_LT(centreAlpha, 0.01);
}

// The window camera sees the full camera's image of its pixels, each cut into sub-pixels.
TEST(Supersampling, AWindowCameraSeesItsPixelsSubdivided)
{
    CameraSettings c = lookAtCamera(Vec3d(1.0, 2.0, 9.0), Vec3d(0.2, 0.1, 0.0), 64, 36);
    const Camera full(c, Vec3d(0.0));
    const Camera sub = full.window(10, 5, 20, 12, 4);
    EXPECT_EQ(sub.width(), 80);
    EXPECT_EQ(sub.height(), 48);
    for (const Vec3d& p : {Vec3d(0.0), Vec3d(0.5, -0.3, 1.0), Vec3d(-1.0, 0.7, -2.0)}) {
        const Vec2d a = full.rasterFromCamera(full.cameraFromWorldPoint(p));
        const Vec2d b = sub.rasterFromCamera(sub.cameraFromWorldPoint(p));
        EXPECT_NEAR(b.x, (a.x - 10.0) * 4.0, 1e-9);
        EXPECT_NEAR(b.y, (a.y - 5.0) * 4.0, 1e-9);
    }
    EXPECT_THROW(full.window(60, 0, 10, 10, 2), ValueError);
    EXPECT_THROW(full.window(0, 0, 10, 10, 0), ValueError);
}

// Box filtering: colour, alpha and passes averaged, Z the lower median, the rest empty.
TEST(Supersampling, BoxFilteringAveragesTheSubPixels)
{
    detail::Supersampling s;
    s.factor = 2;
    s.x0 = 1;
    s.y0 = 0;
    s.width = 1;
    s.height = 1;
    PassRequest passes;
    passes.depth = passes.transmittance = true;
    Frame sub;
    sub.beauty.width = sub.beauty.height = 2;
    sub.beauty.rgba = {0.4f, 0, 0, 1, 0, 0.4f, 0, 1, 0, 0, 0, 0, 0.8f, 0, 0, 1};
    sub.depth = {3.0f, 1.0f, INFINITY, 2.0f};
    sub.transmittance = {0, 0, 0, 0, 0, 0, 1, 1, 1, 0, 0, 0};
    const Frame out = detail::boxFiltered(sub, s, 3, 2, passes);
    const float* p = out.beauty.pixel(1, 0);
    EXPECT_FLOAT_EQ(p[0], 0.3f);
    EXPECT_FLOAT_EQ(p[1], 0.1f);
    EXPECT_FLOAT_EQ(p[3], 0.75f);
    EXPECT_FLOAT_EQ(out.transmittance[3 * 1], 0.25f);
    EXPECT_FLOAT_EQ(out.depth[1], 2.0f); // of 1, 2, 3, inf
    EXPECT_EQ(out.beauty.pixel(0, 0)[3], 0.0f);
    EXPECT_TRUE(std::isinf(out.depth[0]));
    EXPECT_FLOAT_EQ(out.transmittance[3 * 4], 1.0f);
}

// Where the sub-pixels would not fit the budget, fewer are taken, and the render says so.
TEST(Supersampling, TheBudgetLowersTheSubPixelsAndSaysSo)
{
    // A sheet 400 voxels square at 0.1 pixels a voxel (frame 400 units over 40 pixels): 20 x
    // 20 sub-pixels wanted over about 50 x 50 pixels, 1M of them, against a 64 MB budget's 350k.
    const auto grid = columns(400, 1, 1.0f, [](int, int) { return true; });
    RenderSettings s = absorber(0.5, 32);
    s.maxMemory = 64.0 * 1024 * 1024;
    RenderStats stats;
    renderGrid(grid, orthoDownZ(200.0, 200.0, 100.0, 400.0, 40), s, &stats);
    EXPECT_GT(stats.supersample, 1);
    EXPECT_LT(stats.supersample, 20);
    bool said = false;
    for (const std::string& w : stats.warnings) said = said || w.find("--supersample lowered from 20 to") != std::string::npos;
    EXPECT_TRUE(said);
}

// A deep image cannot average sub-pixels: one sample a pixel, said.
TEST(Supersampling, ADeepImageIsCompositedAtOneSampleAPixelAndSaysSo)
{
    const auto grid = columns(12, 12, 1.0f, [](int, int) { return true; });
    const GridSource source = gridSourceFromOpenVDB(grid);
    PassRequest passes;
    passes.deep = true;
    RenderStats stats;
    Renderer(absorber(1.0, 32)).renderFrame(source, Camera(orthoDownZ(6.0, 6.0, 100.0, 64.0, 16), source.worldCentre()), passes, &stats);
    EXPECT_EQ(stats.supersample, 1);
    ASSERT_FALSE(stats.warnings.empty());
    EXPECT_NE(stats.warnings.back().find("--deep: composited at one sample a pixel"), std::string::npos);
}

// Where the factor falls from 2 to 1 (voxels of --supersample-span pixels), the 2 x 2 frame has
// faded into the one-sample frame: a camera move of 1e-4 changes the image by as little there
// as anywhere. The two frames themselves differ at the dense box's edges.
TEST(Supersampling, TheSubPixelsFadeOutWithoutAJump)
{
    const auto grid = columns(12, 12, 1.0f, [](int, int) { return true; });
    const RenderSettings s = absorber(8.0 / 12.0, 32);
    // 2 pixels a voxel at frame 16 over 32 pixels; just under it (S = 2, mixed) and just over.
    RenderStats under, over;
    const Image a = renderGrid(grid, orthoDownZ(6.0, 6.0, 100.0, 16.0 * (1.0 + 1e-4), 32), s, &under);
    const Image b = renderGrid(grid, orthoDownZ(6.0, 6.0, 100.0, 16.0 * (1.0 - 1e-4), 32), s, &over);
    EXPECT_EQ(under.supersample, 2);
    EXPECT_EQ(over.supersample, 1);
    const Image c = renderGrid(grid, orthoDownZ(6.0, 6.0, 100.0, 16.0 * (1.0 - 3e-4), 32), s);
    EXPECT_LT(maxAbsDiff(a, b), 2.0 * maxAbsDiff(b, c) + 1e-3);
    // Where the fade begins (1.5 pixels a voxel) the 2 x 2 frame alone is drawn, and it differs.
    RenderSettings one = s;
    one.splat.supersample = 1;
    const CameraSettings fadeStart = orthoDownZ(6.0, 6.0, 100.0, 16.0 * 4.0 / 3.0 * (1.0 + 1e-4), 32);
    EXPECT_GT(maxAbsDiff(renderGrid(grid, fadeStart, s), renderGrid(grid, fadeStart, one)), 0.02);
}

// Active tiles count as their voxels: a dense tile's face is as sharp as a voxel's. Their
// lattices follow the sub-pixels, so the factor is lowered until the tiles larger than a leaf
// node make at most 32 kernels a pixel (tileKernelBudget): 16^3 internal tiles of 128^3 seen
// from 12,000 units at 160x90 (voxels of 1/58 pixel) would take 32 x 32 and 1.4e8 kernels;
// they take fewer, without a warning.
// Before they counted, they took none and their opaque faces spread (TilesSeenSmall.*).
TEST(Supersampling, ActiveTilesCountAsVoxelsAndTheirKernelsBoundTheSubPixels)
{
    RenderSettings s;
    for (const int edge : {64, 4096}) {
        auto grid = openvdb::FloatGrid::create(0.0f);
        grid->setGridClass(openvdb::GRID_FOG_VOLUME);
        grid->fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(edge - 1)), 0.5f, true); // tiles, as large as fit
        const GridSource source = gridSourceFromOpenVDB(grid);
        ASSERT_EQ(source.impl().activeVoxels, 0u);
        // A voxel is a quarter of a pixel (orthographic: frame 4 x 64 units over 64 pixels).
        const Camera camera(orthoDownZ(edge / 2.0, edge / 2.0, 1e5, 4.0 * 64.0, 64), source.worldCentre());
        EXPECT_NEAR(detail::medianVoxelPixels(source.impl(), camera, s), 0.25, 1e-9) << edge;
    }
    auto internal = openvdb::FloatGrid::create(0.0f);
    internal->setGridClass(openvdb::GRID_FOG_VOLUME);
    internal->fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(2047)), 0.5f, true);
    const GridSource source = gridSourceFromOpenVDB(internal);
    const Camera far(lookAtCamera(Vec3d(1024.0, 1024.0, 14048.0), Vec3d(1024.0), 160, 90), source.worldCentre());
    std::vector<std::string> warnings;
    const detail::MemoryBudget budget(8e9, "internal");
    const detail::Supersampling sub = detail::chooseSupersampling(source.impl(), far, s, PassRequest{}, budget, warnings);
    EXPECT_LT(sub.voxelPixels, 1.0 / 50.0);
    EXPECT_GT(sub.factor, 1);
    EXPECT_LT(sub.factor, 16);
    EXPECT_TRUE(sub.tileLimited);
    EXPECT_TRUE(warnings.empty());
    // The frame's kernels: TilesSeenSmall.FilesOfTilesSeenFromAfarRenderInSeconds.
}
