/// @file slab_compositor_test.cpp
/// @brief The SIMD slab compositor against the scalar one, its oracle (raster/slab_compositor.h):
///        the same frames within 1e-5 on random splats (sub-pixel, pixel-sized and
///        near-plane-huge footprints, emission, several slabs, every pass and deep samples) and
///        on lit renders of the sample cloud (grey and coloured), and bit-identical across
///        thread counts; each for every SIMD target the CPU has (AVX-512, AVX2), forced in turn.
#include "fixtures.h"

#include "raster/raster.h"
#include "splat_fixtures.h"

#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

constexpr double kTolerance = 1e-5;      // relative to max(1, |scalar value|)
constexpr double kDepthTolerance = 1e-3; // Z pass, world units: 1e-3 of a random splat's slab, 1e-2 of the cloud's

bool haveSimd()
{
    return detail::simdSlabCompositor(1) != nullptr;
}

/// Run @a check once for each SIMD target this CPU has (Highway's AVX3, i.e. AVX-512, and AVX2),
/// the backend's dispatch forced to it.
template <typename Check>
void forEachSimdTarget(Check&& check)
{
    const std::int64_t supported = hwy::SupportedTargets();
    for (const std::int64_t target : {std::int64_t(HWY_AVX3), std::int64_t(HWY_AVX2)}) {
        if (!(supported & target)) continue;
        hwy::SetSupportedTargetsForTest(target);
        SCOPED_TRACE(hwy::TargetName(target));
        EXPECT_STREQ(detail::simdTarget(), hwy::TargetName(target));
        check();
    }
    hwy::SetSupportedTargetsForTest(0);
}

/// @a count random splats in a @a width x @a height image: footprint standard deviations
/// (pixels) in [sigmaLo, sigmaHi] with random tilt and aspect up to 4, peak optical depths in
/// [0, tauMax] (grey or coloured), emission on half of them, 1-3 slabs among the first 24.
detail::SplatSet randomSplats(std::uint32_t seed, int count, int width, int height, double sigmaLo, double sigmaHi,
    double tauMax, bool coloured, int passSources = 0)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    detail::SplatSet set;
    set.slabs = {0.0, 1.0};
    set.passSourceCount = passSources;
    const double cutoff = 9.0; // 3 sigma
    for (int n = 0; n < count; ++n) {
        detail::Splat s{};
        s.cx = float(u(rng) * width);
        s.cy = float(u(rng) * height);
        // Covariance R diag(a^2, b^2) R^T, conic its inverse.
        const double a = sigmaLo + (sigmaHi - sigmaLo) * u(rng), b = a / (1.0 + 3.0 * u(rng)), t = 3.14159 * u(rng);
        const double c = std::cos(t), sn = std::sin(t);
        const double vxx = a * a * c * c + b * b * sn * sn, vyy = a * a * sn * sn + b * b * c * c, vxy = (a * a - b * b) * c * sn;
        const double det = vxx * vyy - vxy * vxy;
        s.qa = float(vyy / det);
        s.qb = float(-vxy / det);
        s.qc = float(vxx / det);
        s.cutoff = float(cutoff);
        const double hx = std::sqrt(cutoff * vxx), hy = std::sqrt(cutoff * vyy);
        s.x0 = std::max(0, int(std::ceil(s.cx - hx - 0.5)));
        s.x1 = std::min(width - 1, int(std::floor(s.cx + hx - 0.5)));
        s.y0 = std::max(0, int(std::ceil(s.cy - hy - 0.5)));
        s.y1 = std::min(height - 1, int(std::floor(s.cy + hy - 0.5)));
        const double grey = tauMax * u(rng);
        const bool emits = u(rng) < 0.5;
        for (int ch = 0; ch < 3; ++ch) {
            s.tau[ch] = float(coloured ? tauMax * u(rng) : grey);
            s.emission[ch] = emits ? s.tau[ch] * float(coloured ? u(rng) : 0.7) : 0.0f;
            s.scatter[ch] = s.tau[ch];
        }
        s.firstSlab = std::int64_t(u(rng) * 24.0);
        s.slabCount = 1 + std::uint32_t(u(rng) * 3.0);
        s.shareOffset = set.shares.size();
        double left = 1.0;
        for (std::uint32_t k = 0; k < s.slabCount; ++k) {
            const double share = k + 1 == s.slabCount ? left : left * u(rng);
            left -= share;
            const double mean = u(rng);
            set.shares.push_back(float(share));
            set.shareMoments.push_back(float(mean));
            set.shareMoments.push_back(float(mean * mean + 0.02 * u(rng)));
        }
        for (int k = 0; k < 3 * passSources; ++k) set.passSources.push_back(s.tau[k % 3] * float(u(rng)));
        set.splats.push_back(s);
    }
    return set;
}

/// The largest difference between two arrays (relative to max(1, |b|), or absolute), and the
/// count past the tolerance (non-finite values must match exactly).
struct Agreement
{
    double worst = 0.0;
    std::size_t beyond = 0;
};

Agreement compare(const float* a, const float* b, std::size_t n, double tolerance, bool relative)
{
    Agreement out;
    for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(b[i]) || !std::isfinite(a[i])) {
            out.beyond += std::memcmp(&a[i], &b[i], sizeof(float)) != 0;
            continue;
        }
        const double e = std::abs(double(a[i]) - double(b[i])) / (relative ? std::max(1.0, std::abs(double(b[i]))) : 1.0);
        out.worst = std::max(out.worst, e);
        out.beyond += e > tolerance;
    }
    return out;
}

void expectAgree(const std::vector<float>& simd, const std::vector<float>& scalar, const std::string& what,
    double tolerance = kTolerance, bool relative = true)
{
    ASSERT_EQ(simd.size(), scalar.size()) << what;
    const Agreement a = compare(simd.data(), scalar.data(), simd.size(), tolerance, relative);
    EXPECT_EQ(a.beyond, 0u) << what << ": worst difference " << a.worst;
}

/// Every part of two frames within the tolerance; deep samples in the same count per pixel.
void expectFramesAgree(const Frame& simd, const Frame& scalar, const std::string& what)
{
    expectAgree(simd.beauty.rgba, scalar.beauty.rgba, what + " beauty");
    // Z is where alpha crosses 0.5 inside a slab: a change dT of the transmittance moves it by
    // dT / (T_front - T_back) of the slab, which magnifies 1e-7 to 1e-4 of a slab in one that
    // barely crosses 0.5. Compared in world units.
    expectAgree(simd.depth, scalar.depth, what + " depth", kDepthTolerance, false);
    expectAgree(simd.transmittance, scalar.transmittance, what + " transmittance");
    expectAgree(simd.shadow, scalar.shadow, what + " shadow");
    expectAgree(simd.emission, scalar.emission, what + " emission");
    ASSERT_EQ(simd.deep.offsets, scalar.deep.offsets) << what;
    std::vector<float> a, b;
    for (std::size_t i = 0; i < simd.deep.samples.size(); ++i) {
        for (const auto* s : {&simd.deep.samples[i], &scalar.deep.samples[i]}) {
            auto& v = s == &simd.deep.samples[i] ? a : b;
            v.insert(v.end(), {s->z, s->zBack, s->r, s->g, s->b, s->a});
        }
    }
    expectAgree(a, b, what + " deep samples");
}

/// Rasterise @a set with the SIMD and the scalar backend.
std::pair<Frame, Frame> bothBackends(const detail::SplatSet& set, int width, int height, const PassRequest& passes,
    RenderSettings settings = RenderSettings())
{
    CameraSettings cam;
    cam.width = width;
    cam.height = height;
    const Camera camera(cam, Vec3d(0.0, 0.0, -10.0));
    detail::RasterStats stats;
    settings.simd = true;
    Frame simd = detail::rasterizeSplats(set, camera, settings, passes, stats);
    EXPECT_STRNE(stats.backend, "scalar");
    settings.simd = false;
    Frame scalar = detail::rasterizeSplats(set, camera, settings, passes, stats);
    EXPECT_STREQ(stats.backend, "scalar");
    return {std::move(simd), std::move(scalar)};
}

} // namespace

TEST(SlabCompositor, SimdEqualsScalarOnRandomSplats)
{
    if (!haveSimd()) GTEST_SKIP() << "no SIMD backend on this CPU (Highway target " << detail::simdTarget() << ")";
    forEachSimdTarget([&] {
        struct Case
        {
            const char* name;
            double sigmaLo, sigmaHi, tauMax;
            int count;
        };
        // Sub-pixel footprints (conics past the scalar path's incremental limit, qa > 16),
        // pixel-sized ones, and near-plane ones larger than the image.
        for (const Case& c : {Case{"sub-pixel", 0.1, 0.6, 3.0, 3000}, Case{"pixel-sized", 0.6, 4.0, 1.0, 1500},
                 Case{"huge", 150.0, 2000.0, 0.05, 40}}) {
            for (const bool coloured : {false, true}) {
                const detail::SplatSet set = randomSplats(7, c.count, 77, 45, c.sigmaLo, c.sigmaHi, c.tauMax, coloured);
                const auto [simd, scalar] = bothBackends(set, 77, 45, PassRequest());
                expectFramesAgree(simd, scalar, std::string(c.name) + (coloured ? " coloured" : " grey"));
                EXPECT_GT(std::count_if(scalar.beauty.rgba.begin(), scalar.beauty.rgba.end(), [](float v) { return v > 0.01f; }), 100)
                    << c.name; // something was drawn
            }
        }
    });
}

// Image-space level of detail (--image-lod 1): the coarser levels' samples and their bilinear
// reconstruction agree between the backends as every pixel's do.
TEST(SlabCompositor, SimdEqualsScalarAtEveryImageLevel)
{
    if (!haveSimd()) GTEST_SKIP() << "no SIMD backend on this CPU (Highway target " << detail::simdTarget() << ")";
    forEachSimdTarget([&] {
        RenderSettings settings;
        settings.splat.imageLod = 1.0;
        PassRequest all;
        all.depth = all.transmittance = all.shadow = all.emission = true;
        for (const bool coloured : {false, true}) {
            const detail::SplatSet set = randomSplats(13, 400, 77, 45, 1.0, 12.0, 0.6, coloured, detail::PassLayout(all).count);
            const auto [simd, scalar] = bothBackends(set, 77, 45, all, settings);
            expectFramesAgree(simd, scalar, coloured ? "coloured" : "grey");
        }
    });
}

TEST(SlabCompositor, SimdEqualsScalarInEveryPassAndInDeepSamples)
{
    if (!haveSimd()) GTEST_SKIP() << "no SIMD backend on this CPU (Highway target " << detail::simdTarget() << ")";
    forEachSimdTarget([&] {
        PassRequest all;
        all.depth = all.transmittance = all.shadow = all.emission = all.deep = true;
        const detail::SplatSet set = randomSplats(11, 1500, 50, 37, 0.4, 3.0, 1.5, true, detail::PassLayout(all).count);
        const auto [simd, scalar] = bothBackends(set, 50, 37, all);
        expectFramesAgree(simd, scalar, "all passes");
        EXPECT_GT(scalar.deep.samples.size(), 1000u);
    });
}

TEST(SlabCompositor, SimdEqualsScalarWithTheExpTable)
{
    if (!haveSimd()) GTEST_SKIP() << "no SIMD backend on this CPU (Highway target " << detail::simdTarget() << ")";
    forEachSimdTarget([&] {
        RenderSettings table;
        table.splat.expEvaluation = ExpEvaluation::Table;
        const detail::SplatSet set = randomSplats(5, 800, 40, 30, 0.4, 3.0, 1.0, false);
        const auto [simd, scalar] = bothBackends(set, 40, 30, PassRequest(), table);
        expectFramesAgree(simd, scalar, "exp table");
    });
}

TEST(SlabCompositor, SimdEqualsScalarWithTaperedFootprints)
{
    if (!haveSimd()) GTEST_SKIP() << "no SIMD backend on this CPU (Highway target " << detail::simdTarget() << ")";
    forEachSimdTarget([&] {
        RenderSettings tapered;
        tapered.splat.taper = true;
        const detail::SplatSet set = randomSplats(9, 800, 40, 30, 0.4, 3.0, 1.0, false);
        const auto [simd, scalar] = bothBackends(set, 40, 30, PassRequest(), tapered);
        expectFramesAgree(simd, scalar, "tapered");
        const auto [hard, unused] = bothBackends(set, 40, 30, PassRequest());
        EXPECT_GT(rmse(hard.beauty, scalar.beauty), 1e-4); // the taper did change the footprints
    });
}

TEST(SlabCompositor, SimdEqualsScalarOnLitRenders)
{
    // The light per slab sample (light map), grey and coloured, with the passes.
    if (!haveSimd()) GTEST_SKIP() << "no SIMD backend on this CPU (Highway target " << detail::simdTarget() << ")";
    forEachSimdTarget([&] {
        const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
        const Camera camera = cloudCamera(cloud, 96, 72);
        PassRequest passes;
        passes.depth = passes.shadow = true;
        for (const bool coloured : {false, true}) {
            RenderSettings on;
            if (coloured) {
                on.lights[0].color = Vec3d(0.9, 0.5, 0.2);
                on.medium.scatter = Vec3d(1.5, 1.0, 0.5);
            }
            RenderSettings off = on;
            off.simd = false;
            for (const PassRequest& p : {PassRequest(), passes}) {
                RenderStats a, b;
                const Frame simd = Renderer(on).renderFrame(cloud, camera, p, &a);
                const Frame scalar = Renderer(off).renderFrame(cloud, camera, p, &b);
                EXPECT_NE(a.rasterBackend, "scalar");
                EXPECT_EQ(b.rasterBackend, "scalar");
                expectFramesAgree(simd, scalar, coloured ? "coloured" : "grey");
                EXPECT_GT(alphaSum(scalar.beauty), 100.0);
            }
        }
    });
}

TEST(SlabCompositor, SimdIsBitIdenticalAcrossThreadCounts)
{
    if (!haveSimd()) GTEST_SKIP() << "no SIMD backend on this CPU (Highway target " << detail::simdTarget() << ")";
    forEachSimdTarget([&] {
        const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
        const Camera camera = cloudCamera(cloud, 120, 90);
        RenderSettings one, two;
        one.threads = 1;
        two.threads = 2;
        one.lights[0].color = two.lights[0].color = Vec3d(0.9, 0.5, 0.2);
        RenderStats stats;
        const Image a = Renderer(one).render(cloud, camera, &stats);
        const Image b = Renderer(two).render(cloud, camera);
        EXPECT_NE(stats.rasterBackend, "scalar");
        ASSERT_EQ(a.rgba.size(), b.rgba.size());
        EXPECT_EQ(std::memcmp(a.rgba.data(), b.rgba.data(), a.rgba.size() * sizeof(float)), 0);
    });
}

TEST(SlabCompositor, TerminatedPixelsTakeNoMoreFootprintSamples)
{
    // One 16 x 16 tile: an opaque wall over its left half in slab 0, then fog over the whole tile
    // in slabs 2-21. Behind the wall the fog's footprint rows are cut to the live pixels, so the
    // fog costs about half its samples and the right half is drawn as without the wall.
    constexpr int kSize = 16;
    detail::SplatSet wall, fog, both;
    for (detail::SplatSet* set : {&wall, &fog, &both}) set->slabs = {0.0, 1.0};
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize / 2; ++x)
            for (detail::SplatSet* set : {&wall, &both}) addRoundSplat(*set, float(x) + 0.5f, float(y) + 0.5f, 0.3, 60.0f, 0, kSize, kSize);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, float(kSize));
    for (int n = 0; n < 200; ++n) {
        const float cx = u(rng), cy = u(rng);
        for (detail::SplatSet* set : {&fog, &both}) addRoundSplat(*set, cx, cy, 2.5, 0.02f, 2 + n % 20, kSize, kSize);
    }
    CameraSettings cam;
    cam.width = cam.height = kSize;
    const Camera camera(cam, Vec3d(0.0, 0.0, -10.0));
    for (const bool simd : {false, true}) {
        if (simd && !haveSimd()) continue;
        SCOPED_TRACE(simd ? "SIMD" : "scalar");
        RenderSettings settings;
        settings.simd = simd;
        detail::RasterStats wallStats, fogStats, bothStats;
        detail::rasterizeSplats(wall, camera, settings, PassRequest(), wallStats);
        const Frame fogFrame = detail::rasterizeSplats(fog, camera, settings, PassRequest(), fogStats);
        const Frame bothFrame = detail::rasterizeSplats(both, camera, settings, PassRequest(), bothStats);
        EXPECT_EQ(bothStats.tilesOpaque, 0u); // the tile never turns opaque as a whole
        const double fogBehindWall = double(bothStats.footprintSamples - wallStats.footprintSamples);
        EXPECT_LT(fogBehindWall, 0.6 * double(fogStats.footprintSamples));
        EXPECT_GT(fogBehindWall, 0.4 * double(fogStats.footprintSamples));
        for (int y = 0; y < kSize; ++y)
            for (int x = 0; x < kSize; ++x) {
                const float a = bothFrame.beauty.pixel(x, y)[3];
                if (x < kSize / 2) {
                    EXPECT_GT(a, 0.95f) << x << ", " << y;
                } else {
                    for (int c = 0; c < 4; ++c) EXPECT_NEAR(bothFrame.beauty.pixel(x, y)[c], fogFrame.beauty.pixel(x, y)[c], 1e-6f) << x << ", " << y;
                }
            }
    }
}
