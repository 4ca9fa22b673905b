/// @file image_lod_test.cpp
/// @brief Image-space level of detail (SplatOptions::imageLod, docs/equations.md#image-space-level-of-detail):
///        a magnified Gaussian accumulated at every 2nd, 4th and 8th pixel is its closed form
///        within the bilinear bound 1/(4 n^2) of its peak; an opaque edge stays where it is; the
///        streamed frame, which folds the levels when it parks a tile, equals the whole frame.
#include "fixtures.h"

#include "raster/raster.h"
#include "splat_fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

/// Each pixel's optical depth, from the transmittance pass (red).
std::vector<double> opticalDepths(const Frame& frame)
{
    std::vector<double> tau(frame.transmittance.size() / 3);
    for (std::size_t i = 0; i < tau.size(); ++i) tau[i] = -std::log(double(frame.transmittance[3 * i]));
    return tau;
}

/// @a atLevel: --image-lod-composite (the transmittance pass and Z are written either way).
Frame composite(const detail::SplatSet& set, int width, int height, double imageLod, bool simd, detail::RasterStats& stats, bool atLevel = false)
{
    CameraSettings cam;
    cam.width = width;
    cam.height = height;
    const Camera camera(cam, Vec3d(0.0, 0.0, -10.0));
    RenderSettings settings;
    settings.simd = simd;
    settings.splat.imageLod = imageLod;
    settings.splat.imageLodComposite = atLevel;
    PassRequest passes;
    passes.transmittance = passes.depth = true;
    return detail::rasterizeSplats(set, camera, settings, passes, stats);
}

std::vector<bool> backends()
{
    std::vector<bool> simd{false};
    if (detail::simdSlabCompositor(1)) simd.push_back(true);
    return simd;
}

/// A magnified Gaussian per image level at --image-lod 2 (n = 2.5, 2.25, 2.25 samples of every
/// 2nd, 4th and 8th pixel), and where it lies: off the tiles' and the pixels' grid.
struct MagnifiedCase
{
    double sigma;
    int level;
};
constexpr MagnifiedCase kMagnified[] = {{5.0, 1}, {9.0, 2}, {18.0, 3}};
constexpr int kMagnifiedSize = 112;
constexpr float kMagnifiedX = 55.3f, kMagnifiedY = 57.9f;

/// One round splat of @a sigma pixels and peak optical depth @a tau at (kMagnifiedX, kMagnifiedY).
detail::SplatSet magnifiedGaussian(double sigma, float tau)
{
    detail::SplatSet set;
    set.slabs = {0.0, 1.0};
    addRoundSplat(set, kMagnifiedX, kMagnifiedY, sigma, tau, 0, kMagnifiedSize, kMagnifiedSize);
    return set;
}

} // namespace

// One magnified Gaussian per level (sigma 5, 9 and 18 pixels at --image-lod 2: n = 2.5, 2.25,
// 2.25 samples of every 2nd, 4th and 8th pixel), off the tiles' and the pixels' grid: at every
// pixel the optical depth is the closed form tau exp(-d^2 / 2 sigma^2) within the bilinear
// bound tau / (4 n^2) where the four samples it reads lie inside the cut-off, and within that
// plus the cut-off's step, tau exp(-9 / 2), near the edge. The same image at every pixel
// (off) is the closed form within 1e-5.
TEST(ImageLod, AMagnifiedGaussianIsItsClosedFormWithinTheBilinearBound)
{
    constexpr int kSize = kMagnifiedSize;
    constexpr float kTau = 0.5f;
    const float cx = kMagnifiedX, cy = kMagnifiedY;
    for (const bool simd : backends()) {
        for (const MagnifiedCase& c : kMagnified) {
            SCOPED_TRACE(std::string(simd ? "SIMD" : "scalar") + ", sigma " + std::to_string(c.sigma));
            const detail::SplatSet set = magnifiedGaussian(c.sigma, kTau);
            detail::RasterStats offStats, lodStats;
            const std::vector<double> off = opticalDepths(composite(set, kSize, kSize, 0.0, simd, offStats));
            const std::vector<double> lod = opticalDepths(composite(set, kSize, kSize, 2.0, simd, lodStats));
            // Accumulated at its level alone: a tile's (16 / h + 2)^2 samples (one outside the
            // tile on every side) for its 256 pixels.
            for (int k = 0; k < detail::kImageLevels; ++k) EXPECT_EQ(lodStats.levelSamples[k] > 0, k == c.level) << k;
            EXPECT_EQ(offStats.levelSamples[0], offStats.footprintSamples);
            const double h = double(1 << c.level), n = c.sigma / h, side = 16.0 / h + 2.0;
            EXPECT_LT(double(lodStats.footprintSamples), 1.1 * double(offStats.footprintSamples) * side * side / 256.0);
            const double bound = kTau / (4.0 * n * n), edge = kTau * std::exp(-4.5);
            double worst = 0.0;
            for (int y = 0; y < kSize; ++y)
                for (int x = 0; x < kSize; ++x) {
                    const double dx = x + 0.5 - cx, dy = y + 0.5 - cy, d = std::sqrt(dx * dx + dy * dy);
                    const double exact = d < 3.0 * c.sigma ? kTau * std::exp(-0.5 * d * d / (c.sigma * c.sigma)) : 0.0;
                    const std::size_t i = std::size_t(y) * kSize + std::size_t(x);
                    if (std::abs(d - 3.0 * c.sigma) < 1e-3) continue; // on the cut-off, in float or not
                    ASSERT_NEAR(off[i], exact, 1e-5 + 1e-5 * exact) << x << ", " << y;
                    const bool inside = d + h * std::sqrt(2.0) < 3.0 * c.sigma;
                    ASSERT_LE(std::abs(lod[i] - exact), inside ? bound : bound + edge) << x << ", " << y;
                    worst = std::max(worst, std::abs(lod[i] - exact) / bound);
                }
            // The bound is what the interpolation does, not a loose cap: the peak sits near it.
            EXPECT_GT(worst, 0.3);
        }
    }
}

// An opaque wall: round splats of sigma 4 pixels every 2 pixels over the left half of the
// image, optical depth 8 in sum, at every 2nd pixel (--image-lod 2, n = 2 samples). Across the
// edge the sum is about 8 Phi(-x / 4): |tau''| <= 8 phi(1) / 16 = 0.12 a pixel^2, so bilinear
// samples 2 pixels apart miss it by at most 4 / 8 x 0.12 = 0.06, and alpha (1 - exp(-tau),
// slope <= 1) by as much. Measured: 0.021; the row's 0.5 crossing (alpha's slope there about
// 0.2 a pixel) moves 0.10 pixels. Bounds: 0.03 and 0.15.
TEST(ImageLod, AnOpaqueEdgeStaysWhereItIs)
{
    constexpr int kSize = 64;
    detail::SplatSet set;
    set.slabs = {0.0, 1.0};
    // Sum of the lattice's Gaussians: 2 pi sigma^2 / spacing^2 = 8 pi times each peak.
    const float tau = float(8.0 / (8.0 * 3.14159265));
    for (int j = -6; j < kSize / 2 + 6; ++j)
        for (int i = -6; i < kSize / 4; ++i) addRoundSplat(set, float(2 * i) + 0.7f, float(2 * j) + 0.3f, 4.0, tau, 0, kSize, kSize);
    for (const bool simd : backends()) {
        SCOPED_TRACE(simd ? "SIMD" : "scalar");
        detail::RasterStats offStats, lodStats;
        const Frame off = composite(set, kSize, kSize, 0.0, simd, offStats);
        const Frame lod = composite(set, kSize, kSize, 2.0, simd, lodStats);
        EXPECT_EQ(lodStats.levelSamples[0], 0u);
        EXPECT_GT(lodStats.levelSamples[1], 0u);
        double worst = 0.0, shift = 0.0;
        for (int y = 8; y < kSize - 8; ++y) {
            float crossOff = -1.0f, crossLod = -1.0f;
            for (int x = 0; x + 1 < kSize; ++x) {
                worst = std::max(worst, double(std::abs(lod.beauty.pixel(x, y)[3] - off.beauty.pixel(x, y)[3])));
                for (auto [frame, cross] : {std::pair{&off, &crossOff}, std::pair{&lod, &crossLod}}) {
                    const float a0 = frame->beauty.pixel(x, y)[3], a1 = frame->beauty.pixel(x + 1, y)[3];
                    if (a0 >= 0.5f && a1 < 0.5f) *cross = float(x) + (a0 - 0.5f) / (a0 - a1);
                }
            }
            ASSERT_GT(crossOff, 20.0f);
            ASSERT_LT(crossOff, 44.0f);
            shift = std::max(shift, double(std::abs(crossLod - crossOff)));
        }
        EXPECT_GT(off.beauty.pixel(4, kSize / 2)[3], 0.95f); // opaque (the ray stops at --cutoff)
        EXPECT_LT(worst, 0.03);
        EXPECT_LT(shift, 0.15);
    }
}

// The streamed frame folds the coarser levels into a tile's pending slabs before it parks the
// tile between depth windows: it equals the whole frame within 1e-5, on both backends, lit,
// with the flat passes. The sample cloud from close by (2 windows), and a translucent block of
// 64^3 voxels seen from just outside a face (4 windows, every level used, kernels that the
// windows' ends cut through; without the fold at the park the block's frame is 4.5e-3 off).
TEST(ImageLod, TheStreamedFrameEqualsTheWholeFrame)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    const GridSource block = gridSourceFromOpenVDB(makeFogGrid({0, 0, 0}, {63, 63, 63}, [](const openvdb::Coord& c) {
        return 0.02f + 0.002f * float((c.x() * 7 + c.y() * 3 + c.z()) % 20); // translucent
    }, 0.01));
    PassRequest passes;
    passes.transmittance = passes.shadow = true;
    const std::pair<const GridSource*, Camera> views[] = {
        {&cloud, Camera(lookAtCamera(Vec3d(0.25, 0.15, 0.9), Vec3d(0.0), 160, 120), cloud.worldCentre())},
        {&block, Camera(lookAtCamera(Vec3d(0.3, 0.34, 0.7), Vec3d(0.32, 0.32, 0.0), 96, 72), block.worldCentre())}};
    for (const bool simd : backends())
        for (const auto& [grid, camera] : views) {
            SCOPED_TRACE(std::string(simd ? "SIMD" : "scalar") + (grid == &cloud ? ", cloud" : ", block"));
            RenderSettings s;
            s.simd = simd;
            s.splat.imageLod = 1.0;
            s.splat.imageLodComposite = false; // (on, each frame plans a tile's level from the splats it knows)
            RenderStats streamedStats, wholeStats;
            s.cull = true;
            const Frame streamed = Renderer(s).renderFrame(*grid, camera, passes, &streamedStats);
            s.cull = false;
            const Frame whole = Renderer(s).renderFrame(*grid, camera, passes, &wholeStats);
            ASSERT_TRUE(streamedStats.streamed);
            EXPECT_GT(streamedStats.windows, 1u);
            int levels = 0;
            for (int k = 1; k < detail::kImageLevels; ++k) levels += wholeStats.footprintSamplesAtLevel[k] > 0;
            EXPECT_GE(levels, 2);
            EXPECT_GT(alphaSum(whole.beauty), 50.0);
            for (const auto& [a, b] : {std::pair{&streamed.beauty.rgba, &whole.beauty.rgba},
                     std::pair{&streamed.transmittance, &whole.transmittance}, std::pair{&streamed.shadow, &whole.shadow}}) {
                ASSERT_EQ(a->size(), b->size());
                for (std::size_t i = 0; i < a->size(); ++i) ASSERT_NEAR((*a)[i], (*b)[i], 1e-5 * std::max(1.0f, std::abs((*b)[i]))) << i;
            }
        }
}

// Compositing at a coarser level (--image-lod-composite): one magnified Gaussian per level,
// composited at that level's samples, its alpha reconstructed at the pixels. At a sample the
// alpha is exact, 1 - exp(-f), f = tau exp(-d^2 / 2 sigma^2); bilinear samples h apart miss
// it by at most h^2 / 8 (|a_xx| + |a_yy|), and |a''| = exp(-f) |f'' - f'^2| <= (tau + tau^2 / e)
// / sigma^2, so by (tau + tau^2 / e) / (4 n^2), n = sigma / h (plus the cut-off's step where a
// cell straddles it). The (pixel, slab) composites fall to the level's (16 / h + 2)^2 a tile.
TEST(ImageLodComposite, AMagnifiedGaussianIsItsClosedFormWithinTheBilinearBound)
{
    constexpr int kSize = kMagnifiedSize;
    constexpr float kTau = 1.5f;
    const float cx = kMagnifiedX, cy = kMagnifiedY;
    for (const bool simd : backends()) {
        for (const MagnifiedCase& c : kMagnified) {
            SCOPED_TRACE(std::string(simd ? "SIMD" : "scalar") + ", sigma " + std::to_string(c.sigma));
            const detail::SplatSet set = magnifiedGaussian(c.sigma, kTau);
            detail::RasterStats offStats, lodStats;
            const Frame off = composite(set, kSize, kSize, 0.0, simd, offStats);
            const Frame lod = composite(set, kSize, kSize, 2.0, simd, lodStats, true);
            for (int k = 0; k < detail::kImageLevels; ++k) EXPECT_EQ(lodStats.levelComposites[k] > 0, k == c.level) << k;
            EXPECT_EQ(offStats.levelComposites[0], offStats.slabComposites);
            const double h = double(1 << c.level), n = c.sigma / h, side = 16.0 / h + 2.0;
            EXPECT_LT(double(lodStats.slabComposites), 1.1 * double(offStats.slabComposites) * side * side / 256.0);
            const double bound = (kTau + kTau * kTau / std::exp(1.0)) / (4.0 * n * n), edge = kTau * std::exp(-4.5);
            double worst = 0.0;
            for (int y = 0; y < kSize; ++y)
                for (int x = 0; x < kSize; ++x) {
                    const double dx = x + 0.5 - cx, dy = y + 0.5 - cy, d = std::sqrt(dx * dx + dy * dy);
                    if (std::abs(d - 3.0 * c.sigma) < 1e-3) continue; // on the cut-off, in float or not
                    const double exact = d < 3.0 * c.sigma ? 1.0 - std::exp(-kTau * std::exp(-0.5 * d * d / (c.sigma * c.sigma))) : 0.0;
                    const double alpha = lod.beauty.pixel(x, y)[3];
                    ASSERT_NEAR(off.beauty.pixel(x, y)[3], exact, 1e-5) << x << ", " << y;
                    const bool inside = d + h * std::sqrt(2.0) < 3.0 * c.sigma;
                    ASSERT_LE(std::abs(alpha - exact), inside ? bound : bound + edge) << x << ", " << y;
                    worst = std::max(worst, std::abs(alpha - exact) / bound);
                    // The transmittance pass is the same reconstruction (grey: 1 - alpha).
                    ASSERT_NEAR(lod.transmittance[3 * (std::size_t(y) * kSize + std::size_t(x))], 1.0 - alpha, 1e-6);
                }
            EXPECT_GT(worst, 0.1);
            // Z: where alpha crossed 0.5, within the slab (one slab: its crossing's depth).
            int crossed = 0;
            for (std::size_t i = 0; i < lod.depth.size(); ++i) crossed += std::isfinite(lod.depth[i]);
            EXPECT_GT(crossed, 0);
        }
    }
}

// A tile composited at a coarser level goes on at its pixels when a narrower footprint arrives
// (leaveLevel). Streamed in two windows: a wide Gaussian (sigma 9, level 2) in front, alone in
// the first window, then a narrow one (sigma 1.5, level 0) behind it in the second. The second
// window's tiles start at the level and leave it at the narrow splat: against every pixel
// composited at its pixels (off) the image differs by no more than the wide one's bound, and
// the narrow one's pixels keep their detail (its peak's alpha within that bound too).
TEST(ImageLodComposite, ANarrowerFootprintTakesTheTileToItsPixels)
{
    constexpr int kSize = 96;
    const float tauWide = 0.8f, tauNarrow = 2.0f;
    detail::SplatSet first, second;
    first.slabs = second.slabs = {0.0, 1.0};
    addRoundSplat(first, 47.3f, 45.1f, 9.0, tauWide, 0, kSize, kSize);
    addRoundSplat(second, 50.5f, 48.5f, 1.5, tauNarrow, 3, kSize, kSize);
    CameraSettings cam;
    cam.width = cam.height = kSize;
    const Camera camera(cam, Vec3d(0.0, 0.0, -10.0));
    PassRequest passes;
    passes.transmittance = true;
    for (const bool simd : backends()) {
        SCOPED_TRACE(simd ? "SIMD" : "scalar");
        std::vector<Frame> frames;
        std::vector<detail::RasterStats> stats(2);
        for (const bool atLevel : {false, true}) {
            RenderSettings settings;
            settings.simd = simd;
            settings.splat.imageLod = 2.0;
            settings.splat.imageLodComposite = atLevel;
            detail::StreamedRaster raster(camera, settings, passes, {}, false, true, first.slabs, nullptr);
            raster.composite(first, 3, nullptr);
            raster.composite(second, std::numeric_limits<std::int64_t>::max(), nullptr);
            frames.push_back(raster.finish(stats[atLevel]));
        }
        EXPECT_GT(stats[1].levelComposites[2], 0u);
        EXPECT_GT(stats[1].levelComposites[0], 0u); // the narrow splat's slab, at the pixels
        const double n = 9.0 / 4.0, bound = (tauWide + tauWide * tauWide / std::exp(1.0)) / (4.0 * n * n);
        double worst = 0.0;
        for (int y = 0; y < kSize; ++y)
            for (int x = 0; x < kSize; ++x) worst = std::max(worst, double(std::abs(frames[1].beauty.pixel(x, y)[3] - frames[0].beauty.pixel(x, y)[3])));
        EXPECT_LT(worst, bound);
        EXPECT_GT(worst, 0.0); // the wide one was composited at its level
        EXPECT_NEAR(frames[1].beauty.pixel(50, 48)[3], frames[0].beauty.pixel(50, 48)[3], bound);
        EXPECT_GT(frames[0].beauty.pixel(50, 48)[3] - frames[0].beauty.pixel(44, 42)[3], 0.3); // the narrow peak stands out
    }
}

// A lit volume composited at coarser levels (the sample cloud from close by: most tiles at
// levels 1-3): the light is looked up on the samples' own rays (sampleX, sampleY), so the image
// stays within the interpolation error of compositing every pixel: RMS under 1e-3 (measured
// 0.9e-4 whole, 1.5e-4 streamed; with the rays traced through the pixels' centres instead,
// 0.1), on both backends, the streamed frame and the whole frame alike.
TEST(ImageLodComposite, ALitVolumeSeenCloseMatchesEveryPixel)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    const Camera camera(lookAtCamera(Vec3d(0.25, 0.15, 0.9), Vec3d(0.0), 160, 120), cloud.worldCentre());
    PassRequest passes;
    for (const bool simd : backends())
        for (const bool cull : {true, false}) {
            SCOPED_TRACE(std::string(simd ? "SIMD" : "scalar") + (cull ? ", streamed" : ", whole"));
            RenderSettings s;
            s.simd = simd;
            s.cull = cull;
            s.splat.imageLod = 0.0;
            const Frame off = Renderer(s).renderFrame(cloud, camera, passes);
            s.splat.imageLod = 1.0;
            s.splat.imageLodComposite = true;
            RenderStats stats;
            const Frame lod = Renderer(s).renderFrame(cloud, camera, passes, &stats);
            EXPECT_GT(stats.slabCompositesAtLevel[1] + stats.slabCompositesAtLevel[2] + stats.slabCompositesAtLevel[3], stats.slabComposites / 2);
            double sum = 0.0;
            for (std::size_t i = 0; i < off.beauty.rgba.size(); ++i) sum += std::pow(double(lod.beauty.rgba[i]) - double(off.beauty.rgba[i]), 2.0);
            const double rms = std::sqrt(sum / double(off.beauty.rgba.size()));
            EXPECT_LT(rms, 1e-3);
            EXPECT_GT(alphaSum(off.beauty), 1000.0);
        }
}
