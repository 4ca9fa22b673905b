/// @file streamed_frame_test.cpp
/// @brief The streamed frame (RenderSettings::cull, docs/architecture.md#the-streamed-frame)
///        against its oracle, the whole frame (cull off): the same image within 1e-5 wherever a
///        pixel was alive, bricks behind opaque tiles never expanded, any thread count, a budget
///        a window fits.
#include "fixtures.h"

#include "projection/projection.h"
#include "raster/raster.h"
#include "shading/shading.h"
#include "source/source.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

/// Largest |a - b| / max(1, |b|) over two float arrays of one size, +inf on NaN or size mismatch.
double relativeDiff(const std::vector<float>& a, const std::vector<float>& b)
{
    if (a.size() != b.size()) return INFINITY;
    double worst = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        if (a[i] == b[i]) continue; // infinities (Z where nothing is)
        const double d = std::abs(double(a[i]) - double(b[i])) / std::max(1.0, std::abs(double(b[i])));
        worst = std::max(worst, std::isnan(d) ? INFINITY : d);
    }
    return worst;
}

struct Pair
{
    Frame streamed, whole;
    RenderStats streamedStats, wholeStats;
};

Pair renderBoth(const GridSource& grid, const Camera& camera, RenderSettings settings, const PassRequest& passes = {})
{
    Pair p;
    settings.cull = true;
    p.streamed = Renderer(settings).renderFrame(grid, camera, passes, &p.streamedStats);
    settings.cull = false;
    p.whole = Renderer(settings).renderFrame(grid, camera, passes, &p.wholeStats);
    return p;
}

/// An opaque wall (x 0..@a wallEnd, y 0..127, z 60..67) over a fog block (x, y 40..87, z 0..55)
/// behind it, seen from above (+z): orthoDownZ(64, 64, 200, 160, 128) sees the wall over the
/// fog's tiles and beyond (all of them for the default @a wallEnd, half for 63).
openvdb::FloatGrid::Ptr wallOverFog(openvdb::FloatGrid::Ptr* wallOnly = nullptr, openvdb::FloatGrid::Ptr* fogOnly = nullptr, int wallEnd = 127)
{
    const auto wall = [](const openvdb::Coord& c) { return c.z() >= 60 ? 50.0f : 0.5f; };
    auto grid = makeFogGrid({0, 0, 60}, {wallEnd, 127, 67}, wall, 1.0);
    auto fog = makeFogGrid({40, 40, 0}, {87, 87, 55}, wall, 1.0);
    if (wallOnly) *wallOnly = grid->deepCopy();
    if (fogOnly) *fogOnly = fog;
    auto acc = grid->getAccessor();
    for (auto it = fog->cbeginValueOn(); it; ++it) acc.setValueOn(it.getCoord(), *it);
    return grid;
}

} // namespace

// The sample cloud from near and far, perspective and orthographic, lit, with every flat pass,
// on both rasteriser backends: the streamed frame is the whole frame within 1e-5.
TEST(StreamedFrame, EqualsTheWholeFrameOnTheSampleCloud)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    PassRequest passes;
    passes.transmittance = passes.shadow = passes.emission = true;
    CameraSettings ortho = orthoDownZ(0.0, 0.0, 5.0, 3.0, 96);
    const Camera cameras[] = {cloudCamera(cloud, 160, 120), Camera(lookAtCamera(Vec3d(0.3, 0.2, 1.2), Vec3d(0.0), 128, 96), cloud.worldCentre()),
        Camera(ortho, cloud.worldCentre())};
    for (const bool simd : {true, false}) {
        for (const Camera& camera : cameras) {
            RenderSettings s;
            s.simd = simd;
            s.medium.emission = Vec3d(0.1, 0.05, 0.0);
            const Pair p = renderBoth(cloud, camera, s, passes);
            ASSERT_TRUE(p.streamedStats.streamed);
            ASSERT_FALSE(p.wholeStats.streamed);
            EXPECT_GT(alphaSum(p.whole.beauty), 50.0);
            EXPECT_LE(relativeDiff(p.streamed.beauty.rgba, p.whole.beauty.rgba), 1e-5) << "simd " << simd;
            EXPECT_LE(relativeDiff(p.streamed.transmittance, p.whole.transmittance), 1e-5);
            EXPECT_LE(relativeDiff(p.streamed.shadow, p.whole.shadow), 1e-5);
            EXPECT_LE(relativeDiff(p.streamed.emission, p.whole.emission), 1e-5);
            EXPECT_EQ(p.streamedStats.warnings.size(), p.wholeStats.warnings.size()); // as many kinds of clamp
            for (const std::string& w : p.streamedStats.warnings) EXPECT_EQ(w.find("in front of their window"), std::string::npos) << w;
        }
    }
}

// Two lights, one across the view and one behind the camera, coloured: each map is marched on
// the first lookups that read it, on both backends; the streamed frame is the whole frame.
TEST(StreamedFrame, SeveralLightsAreEachMarchedOnDemand)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    const Camera camera(lookAtCamera(Vec3d(0.3, 0.2, 1.2), Vec3d(0.0), 128, 96), cloud.worldCentre());
    for (const bool simd : {true, false}) {
        RenderSettings s;
        s.simd = simd;
        s.lights.resize(2);
        s.lights[0].direction = Vec3d(1.0, 0.3, 0.2);
        s.lights[1].direction = Vec3d(-0.2, 0.4, 1.0);
        s.lights[1].color = Vec3d(0.2, 0.4, 0.9);
        const Pair p = renderBoth(cloud, camera, s);
        EXPECT_GT(p.streamedStats.lightRaysMarched, 0u);
        EXPECT_LT(p.streamedStats.lightRaysMarched, p.streamedStats.lightRays);
        EXPECT_EQ(p.wholeStats.lightRaysMarched, p.wholeStats.lightRays);
        EXPECT_GT(alphaSum(p.whole.beauty), 50.0);
        EXPECT_LE(relativeDiff(p.streamed.beauty.rgba, p.whole.beauty.rgba), 1e-5) << "simd " << simd;
    }
}

// Z and deep samples, which the streamed frame writes as each tile finishes.
TEST(StreamedFrame, DepthAndDeepSamplesEqualTheWholeFrames)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    PassRequest passes;
    passes.depth = passes.deep = true;
    const Pair p = renderBoth(cloud, cloudCamera(cloud, 96, 72), RenderSettings(), passes);
    EXPECT_LE(relativeDiff(p.streamed.beauty.rgba, p.whole.beauty.rgba), 1e-5);
    ASSERT_EQ(p.streamed.depth.size(), p.whole.depth.size());
    for (std::size_t i = 0; i < p.whole.depth.size(); ++i) {
        if (p.streamed.depth[i] != p.whole.depth[i]) {
            EXPECT_NEAR(p.streamed.depth[i], p.whole.depth[i], 1e-3) << i;
        }
    }
    EXPECT_EQ(p.streamed.deep.offsets, p.whole.deep.offsets);
    ASSERT_EQ(p.streamed.deep.samples.size(), p.whole.deep.samples.size());
    double worst = 0.0;
    for (std::size_t i = 0; i < p.whole.deep.samples.size(); ++i) {
        const DeepSample &a = p.streamed.deep.samples[i], &b = p.whole.deep.samples[i];
        for (const auto& [x, y] : {std::pair{a.r, b.r}, {a.g, b.g}, {a.b, b.b}, {a.a, b.a}, {a.z, b.z}}) worst = std::max(worst, double(std::abs(x - y)));
    }
    EXPECT_LE(worst, 1e-5);
}

// An opaque wall in front of fog: the fog's bricks are never expanded, and the image is the
// whole frame's. Breaking the occlusion summary (StreamedRaster::hidden always false) fails
// the counters; a wrong bound (a brick culled where its splats reach a live pixel) the image.
TEST(StreamedFrame, AnOpaqueWallHidesTheFogBehindIt)
{
    openvdb::FloatGrid::Ptr wallOnly, fogOnly;
    const GridSource grid = gridSourceFromOpenVDB(wallOverFog(&wallOnly, &fogOnly));
    const Camera camera(orthoDownZ(64.0, 64.0, 200.0, 160.0, 128), grid.worldCentre());
    RenderSettings s;
    s.lights.clear();
    s.splat.lodPixels = 0.0; // voxel kernels: a brick reaches 2.5 voxels beyond its voxels
    const Pair p = renderBoth(grid, camera, s);
    const std::uint64_t fogBricks = fogOnly->tree().leafCount(), wallBricks = wallOnly->tree().leafCount();
    std::printf("wall %llu bricks, fog %llu; expanded %llu, hidden %llu, windows %llu, outside %llu; kernels %llu (merged %llu, halo %llu) vs %llu (%llu, %llu), tiles opaque %llu of %llu\n",
        (unsigned long long)wallBricks, (unsigned long long)fogBricks, (unsigned long long)p.streamedStats.bricksExpanded,
        (unsigned long long)p.streamedStats.bricksHidden, (unsigned long long)p.streamedStats.windows, (unsigned long long)p.streamedStats.bricksOutside,
        (unsigned long long)p.streamedStats.kernels, (unsigned long long)p.streamedStats.mergedKernels, (unsigned long long)p.streamedStats.haloKernels,
        (unsigned long long)p.wholeStats.kernels, (unsigned long long)p.wholeStats.mergedKernels, (unsigned long long)p.wholeStats.haloKernels,
        (unsigned long long)p.streamedStats.screenTilesOpaque, (unsigned long long)p.streamedStats.screenTiles);
    EXPECT_EQ(p.streamedStats.bricks, p.wholeStats.activeTiles + wallBricks + fogBricks);
    EXPECT_GE(p.streamedStats.bricksHidden, fogBricks);
    EXPECT_LE(p.streamedStats.bricksExpanded, wallBricks);
    EXPECT_LT(p.streamedStats.kernels, p.wholeStats.kernels * 2 / 3);
    EXPECT_LE(relativeDiff(p.streamed.beauty.rgba, p.whole.beauty.rgba), 1e-5);
    EXPECT_GT(alphaSum(p.whole.beauty), 0.3 * 128 * 128);
    // Seen from below, the fog is in front: nothing is hidden behind the open fog.
    const Camera below(lookAtCamera(Vec3d(64.0, 64.0, -150.0), Vec3d(64.0, 64.0, 30.0), 96, 96), grid.worldCentre());
    const Pair q = renderBoth(grid, below, s);
    EXPECT_LE(relativeDiff(q.streamed.beauty.rgba, q.whole.beauty.rgba), 1e-5);
}

// Lit, a wall over half the fog: the fog's slabs behind the wall's stopped pixels look nothing
// up, and their light is never marched (light on demand marches on a slab's first lookup, for
// its lit pixels only); the image is the whole frame's.
TEST(StreamedFrame, LightIsMarchedOnlyWhereLivePixelsLookItUp)
{
    // The wall covers half the fog (x < 64): the bricks across its edge are expanded, and their
    // splats under the wall lie over opaque tiles.
    const GridSource grid = gridSourceFromOpenVDB(wallOverFog(nullptr, nullptr, 63));
    const Camera camera(orthoDownZ(64.0, 64.0, 200.0, 160.0, 128), grid.worldCentre());
    RenderSettings s;
    s.splat.lodPixels = 0.0;
    const Pair p = renderBoth(grid, camera, s);
    std::printf("light rays marched %llu of %llu (whole frame %llu)\n", (unsigned long long)p.streamedStats.lightRaysMarched,
        (unsigned long long)p.streamedStats.lightRays, (unsigned long long)p.wholeStats.lightRaysMarched);
    // Measured: 4,752 of 10,920 rays. 5,392 when each slab marks its whole dirty box, lit
    // pixels or not; 7,008 when each window was lit before it was composited.
    EXPECT_LE(p.streamedStats.lightRaysMarched, 5000u);
    EXPECT_EQ(p.wholeStats.lightRaysMarched, p.wholeStats.lightRays);
    EXPECT_LE(relativeDiff(p.streamed.beauty.rgba, p.whole.beauty.rgba), 1e-5);
    EXPECT_GT(alphaSum(p.whole.beauty), 0.3 * 128 * 128);
}

TEST(StreamedFrame, ThreadCountDoesNotChangeTheImage)
{
    const GridSource grid = gridSourceFromOpenVDB(wallOverFog());
    const Camera camera(lookAtCamera(Vec3d(60.0, 70.0, 260.0), Vec3d(64.0, 64.0, 30.0), 96, 80), grid.worldCentre());
    RenderSettings one, two;
    one.threads = 1;
    two.threads = 2;
    one.splat.lodPixels = two.splat.lodPixels = 0.0;
    RenderStats stats;
    const Image a = Renderer(one).render(grid, camera, &stats);
    const Image b = Renderer(two).render(grid, camera);
    ASSERT_TRUE(stats.streamed);
    EXPECT_GT(stats.bricksHidden, 0u);
    ASSERT_EQ(a.rgba.size(), b.rgba.size());
    EXPECT_EQ(std::memcmp(a.rgba.data(), b.rgba.data(), a.rgba.size() * sizeof(float)), 0);
}

// A budget below what all kernels need (the whole frame stops with BudgetError) but above a
// window's: the streamed frame renders, the image it would with all the memory.
TEST(StreamedFrame, RendersWithinABudgetTheWholeFrameExceeds)
{
    const GridSource block = gridSourceFromOpenVDB(makeFogGrid({0, 0, 0}, {99, 99, 99}, [](const openvdb::Coord& c) {
        return 0.05f + 0.002f * float((c.x() * 7 + c.y() * 3 + c.z()) % 50);
    }, 0.01));
    const Camera camera(lookAtCamera(Vec3d(1.5, 1.2, 2.5), Vec3d(0.5), 64, 48), block.worldCentre());
    RenderSettings tight;
    tight.splat.lodPixels = 0.0; // a kernel a voxel
    tight.shadow.step = 1.0;      // a light map within a quarter of the budget, as with all the memory
    tight.shadow.resolution = 2.0;
    tight.maxMemory = 64.0 * 1024 * 1024; // 1M kernels need 256 MB
    tight.cull = false;
    EXPECT_THROW(Renderer(tight).render(block, camera), BudgetError);
    tight.cull = true;
    RenderStats stats;
    const Image streamed = Renderer(tight).render(block, camera, &stats);
    EXPECT_GE(stats.windows, 4u);
    for (const std::string& w : stats.warnings) ADD_FAILURE() << w;
    RenderSettings roomy = tight;
    roomy.maxMemory = 0.0;
    roomy.cull = false;
    const Image whole = Renderer(roomy).render(block, camera);
    EXPECT_LE(relativeDiff(streamed.rgba, whole.rgba), 1e-5);
    EXPECT_GT(alphaSum(whole), 0.5 * 64 * 48);
}

// Memory follows the window, not the grid: a 2.1M-voxel block whose kernels (256 bytes each,
// 537 MB) fit the machine's budget many times over is still composited in windows of about
// kWindowBytes (128 MiB, 524,288 kernels), plus the brick layer that ends a window on one slab,
// halo kernels and the splats carried from the window before: 679k splats at most. Without
// that bound the block, translucent, goes in one window after the first three: 2.0M splats.
TEST(StreamedFrame, HoldsAWindowOfSplatsWhateverTheGridsSize)
{
    const GridSource block = gridSourceFromOpenVDB(makeFogGrid({0, 0, 0}, {127, 127, 127}, [](const openvdb::Coord& c) {
        return 0.02f + 0.001f * float((c.x() * 7 + c.y() * 3 + c.z()) % 20); // above --cutoff, translucent
    }, 0.01));
    const Camera camera(lookAtCamera(Vec3d(0.64, 0.64, 4.0), Vec3d(0.64), 48, 48), block.worldCentre());
    RenderSettings s;
    s.splat.lodPixels = 0.0; // a kernel a voxel
    s.splat.supersample = 1; // every brick in view: sub-pixel tiles turn opaque sooner and hide some
    s.lights.clear();
    RenderStats stats;
    Renderer(s).render(block, camera, &stats);
    ASSERT_TRUE(stats.streamed);
    EXPECT_GE(stats.splats, 2000000u);
    EXPECT_GT(stats.splatsInFlight, 100000u);
    EXPECT_LE(stats.splatsInFlight, 524288u * 3u / 2u);
}

// Every shared fog asset, from the assets' README cameras, at a small size: the streamed
// frame is the whole frame within 1e-5. Skipped without the assets.
TEST(StreamedFrame, EqualsTheWholeFrameOnTheSharedAssets)
{
    const std::string dir = assetsDir();
    if (dir.empty()) GTEST_SKIP() << "shared assets not found (set VDB_EWA_ASSETS)";
    struct Asset
    {
        const char* file;
        Vec3d eye, target;
    };
    const Asset assets[] = {{"smoke.vdb", {-7.381, 40.48, 237.4}, {-7.381, 40.48, 0.4762}}, {"pyro.vdb", {0.225, 2.175, 15.75}, {0.225, 2.175, -0.225}},
        {"pig.vdb", {0, 0, 2.49}, {0, 0, 0}}, {"fog_tommy_v5.vdb", {0, 0.875, 3.65}, {0, 0.875, 0}},
        {"smoke_double.vdb", {63.5, 31.5, 318}, {63.5, 31.5, 31.5}}, {"brain_mri.vdb", {62.5, 70.5, 281}, {62.5, 70.5, 41.5}}};
    for (const Asset& a : assets) {
        const GridSource grid = GridSource::open(dir + "/" + a.file);
        for (const bool framed : {true, false}) { // the README's camera, and the default one
            CameraSettings c = lookAtCamera(a.eye, a.target, 240, 135);
            if (!framed) {
                c = CameraSettings{};
                c.width = 240;
                c.height = 135;
            }
            const Camera camera(c, grid.worldCentre());
            const Pair p = renderBoth(grid, camera, RenderSettings());
            std::printf("%s (%s camera): %llu of %llu bricks expanded, %llu hidden; max relative difference %.2g\n", a.file,
                framed ? "README" : "default", (unsigned long long)p.streamedStats.bricksExpanded, (unsigned long long)p.streamedStats.bricks,
                (unsigned long long)p.streamedStats.bricksHidden, relativeDiff(p.streamed.beauty.rgba, p.whole.beauty.rgba));
            EXPECT_TRUE(p.streamedStats.streamed) << a.file;
            EXPECT_LE(relativeDiff(p.streamed.beauty.rgba, p.whole.beauty.rgba), 1e-5) << a.file;
        }
    }
}


// Light on demand (lib/raster/light_on_demand.h): for the pixel rectangle and slabs of one
// splat at a time, every light-map ray a lookup can read (the four around a point on a pixel
// ray of the rectangle, at a distance within the slabs) is marched by ensureMarched(lookupBox),
// for a light across the view, from a perspective and an orthographic camera; and far fewer
// than all rays are.
TEST(StreamedFrame, LightOnDemandMarchesEveryRayALookupReads)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    const GridSource::Impl& fog = cloud.impl();
    RenderSettings s;
    s.lights[0].direction = Vec3d(1.0, 0.3, 0.2); // across the view: deeper points move across the map
    s.shadow.resolution = 0.25;                   // rays a quarter voxel apart: many tiles of rays
    const detail::KernelSet kernels = detail::extractKernels(fog, s);
    const Camera cameras[] = {Camera(lookAtCamera(Vec3d(0.3, 0.2, 1.2), Vec3d(0.0), 128, 96), cloud.worldCentre()),
        Camera(orthoDownZ(0.0, 0.0, 5.0, 3.0, 96), cloud.worldCentre())};
    std::uint64_t checked = 0, spanning = 0;
    for (const Camera& camera : cameras) {
        const bool perspective = camera.projection() == Projection::Perspective;
        const detail::SplatSet all = detail::projectSplats(fog, kernels, {}, camera, s);
        ASSERT_GT(all.splats.size(), 1000u);
        for (std::size_t n = 0; n < all.splats.size(); n += 97) {
            const detail::Splat& sp = all.splats[n];
            spanning += sp.slabCount > 1 ? 1 : 0;
            const double z0 = all.slabs.start(sp.firstSlab), z1 = all.slabs.start(sp.firstSlab + std::int64_t(sp.slabCount));
            const detail::LightMap map(fog, s, 0, nullptr, detail::kLightMapPointBudget, true);
            Vec3d lo, hi;
            detail::lookupBox(camera, map, sp.x0 + 0.5, sp.y0 + 0.5, sp.x1 + 0.5, sp.y1 + 0.5, z0, z1, lo, hi);
            map.ensureMarched(lo, hi);
            ASSERT_LT(map.raysMarched(), map.rays() / 4) << "splat " << n;
            for (int y = sp.y0; y <= sp.y1; y += std::max(1, (sp.y1 - sp.y0) / 4))
                for (int x = sp.x0; x <= sp.x1; x += std::max(1, (sp.x1 - sp.x0) / 4))
                    for (int k = 0; k <= 8; ++k) {
                        // A perspective camera's slabs are in distance along the pixel's ray, an
                        // orthographic one's in camera depth.
                        Vec3d origin, direction;
                        camera.worldRay(x + 0.5, y + 0.5, origin, direction);
                        const double z = z0 + (z1 - z0) * k / 8.0;
                        const Vec3d p = perspective ? camera.eye() + z * glm::normalize(direction)
                                                    : origin + (z - camera.cameraFromWorldPoint(origin).z) * direction;
                        const Vec3d q = map.coordinates(p);
                        const int i = int(std::floor(q.x)), j = int(std::floor(q.y));
                        for (int dj = 0; dj <= 1; ++dj)
                            for (int di = 0; di <= 1; ++di) {
                                const int ri = i + di, rj = j + dj;
                                if (ri < 0 || rj < 0 || ri >= map.raysU() || rj >= map.raysV()) continue;
                                ASSERT_TRUE(map.marched(ri, rj)) << "splat " << n << " pixel " << x << "," << y << " distance " << z << ": ray " << ri << "," << rj;
                                ++checked;
                            }
                    }
        }
    }
    EXPECT_GT(checked, 2000u);
    EXPECT_GT(spanning, 20u); // splats over several slabs, whose deeper lookups move across the map
}
