/// @file passes_test.cpp
/// @brief The passes beside the beauty (docs/output.md) against analytic slabs and identities
///        of the optical model: Z of a uniform slab, RGB transmittance, the shadow pass as the
///        beauty of a white albedo-1 medium, emission alone and added, deep samples that
///        flatten back to the beauty.
#include "fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

constexpr double kVoxel = 0.1;

/// A slab of 41 x 41 x 40 voxels of density 1, top face at z = 0.05 (voxel centres k * 0.1,
/// k = -39..0), seen orthographically from z = 10 (camera depth of the top face 9.95).
GridSource slabGrid() { return gridSourceFromOpenVDB(makeBoxGrid(openvdb::Coord(-20, -20, -39), openvdb::Coord(20, 20, 0), 1.0f, kVoxel)); }

Camera slabCamera(int res = 8)
{
    return Camera(orthoDownZ(0.0, 0.0, 10.0, 1.0, res), Vec3d(0.0));
}

PassRequest allFlatPasses()
{
    PassRequest p;
    p.depth = p.transmittance = p.shadow = p.emission = true;
    return p;
}

/// Front-to-back "over" of a deep pixel's samples: premultiplied RGBA.
std::array<double, 4> flatten(const DeepImage& deep, int x, int y)
{
    std::array<double, 4> out{0, 0, 0, 0};
    const std::size_t i = std::size_t(y) * std::size_t(deep.width) + std::size_t(x);
    for (std::uint64_t k = deep.offsets[i]; k < deep.offsets[i + 1]; ++k) {
        const DeepSample& s = deep.samples[k];
        const double t = 1.0 - out[3];
        out[0] += t * s.r;
        out[1] += t * s.g;
        out[2] += t * s.b;
        out[3] += t * s.a;
    }
    return out;
}

} // namespace

TEST(Passes, DepthIsWhereAlphaReachesOneHalfInAUniformSlab)
{
    // Pure absorber, extinction 0.1 per voxel: alpha = 0.5 at ln 2 / 0.1 = 6.93 voxels below
    // the top face, camera depth 9.95 + 0.693.
    const GridSource slab = slabGrid();
    const Camera camera = slabCamera();
    const double expected = 10.0 - 0.05 + std::log(2.0) / 0.1 * kVoxel;
    for (const double slabVoxels : {0.5, 2.0, 8.0}) {
        RenderSettings s = absorberSettings(0.1);
        s.splat.slab = slabVoxels;
        const Frame f = Renderer(s).renderFrame(slab, camera, allFlatPasses());
        ASSERT_EQ(f.depth.size(), 64u);
        for (float z : f.depth) EXPECT_NEAR(z, expected, 0.25 * kVoxel) << "--slab " << slabVoxels;
    }
    RenderSettings reference = absorberSettings(0.1);
    reference.method = Method::RayMarch;
    reference.step = 0.5;
    PassRequest depthOnly;
    depthOnly.depth = true;
    const Frame r = Renderer(reference).renderFrame(slab, camera, depthOnly);
    for (float z : r.depth) EXPECT_NEAR(z, expected, 0.25 * kVoxel) << "raymarch";
    // A thin slab never reaches alpha 0.5: Z is +inf, and +inf where there is nothing.
    const GridSource thin = gridSourceFromOpenVDB(makeBoxGrid(openvdb::Coord(-20, -20, -1), openvdb::Coord(20, 20, 0), 1.0f, kVoxel));
    const Frame t = Renderer(absorberSettings(0.1)).renderFrame(thin, slabCamera(), allFlatPasses());
    for (float z : t.depth) EXPECT_TRUE(std::isinf(z) && z > 0);
}

TEST(Passes, DepthIsCameraDepthForPerspectiveCameras)
{
    // An oblique ray reaches optical depth ln 2 after ln 2 world units, cos(theta) ln 2 deeper
    // in camera depth than the slab's top face (camera depth 9.95 everywhere on the face).
    const GridSource slab = gridSourceFromOpenVDB(makeBoxGrid(openvdb::Coord(-100, -100, -39), openvdb::Coord(100, 100, 0), 1.0f, kVoxel));
    CameraSettings c;
    c.width = c.height = 64; // pixels of 1.8 voxels at the face: Z of one depth, not a spread
    c.translate = Vec3d(0.0, 0.0, 10.0);
    c.lookAt = Vec3d(0.0);
    c.setFieldOfView(60.0);
    const Camera camera(c, Vec3d(0.0));
    RenderSettings s = absorberSettings(0.1);
    s.splat.lodPixels = 0.0; // keep voxels unmerged for an exact face
    const Frame f = Renderer(s).renderFrame(slab, camera, allFlatPasses());
    for (const auto& [x, y] : {std::pair{0, 0}, {32, 32}, {63, 20}, {10, 50}}) {
        const double u = (x + 0.5 - 32.0) / camera.focalPixels(), v = (y + 0.5 - 32.0) / camera.focalPixels();
        const double expected = 10.0 - 0.05 + std::log(2.0) / std::sqrt(1.0 + u * u + v * v);
        EXPECT_NEAR(f.depth[std::size_t(y) * 64 + std::size_t(x)], expected, 0.25 * kVoxel) << x << "," << y;
    }
}

TEST(Passes, TransmittanceIsPerChannelAndAlphaIsItsMean)
{
    // 10 voxels deep, absorb (0.05, 0.1, 0.2): T_c = exp(-10 sigma_c).
    const GridSource slab = gridSourceFromOpenVDB(makeBoxGrid(openvdb::Coord(-20, -20, -9), openvdb::Coord(20, 20, 0), 1.0f, kVoxel));
    RenderSettings s = absorberSettings(0.0);
    s.medium.absorb = Vec3d(0.05, 0.1, 0.2);
    const Frame f = Renderer(s).renderFrame(slab, slabCamera(), allFlatPasses());
    for (std::size_t i = 0; i < 64; ++i) {
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(f.transmittance[3 * i + c], std::exp(-10.0 * s.medium.absorb[c]), 0.01) << "channel " << c;
        }
        const float* t = &f.transmittance[3 * i];
        EXPECT_FLOAT_EQ(f.beauty.rgba[4 * i + 3], 1.0f - (t[0] + t[1] + t[2]) / 3.0f);
    }
}

TEST(Passes, ShadowPassIsTheBeautyOfAWhiteAlbedoOneMedium)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    const Camera camera = cloudCamera(cloud, 96, 64);
    RenderSettings s; // absorb 0, white light 1: the beauty is the composited shadow term
    s.medium.absorb = Vec3d(0.0);
    s.lights[0].color = Vec3d(1.0);
    const Frame f = Renderer(s).renderFrame(cloud, camera, allFlatPasses());
    double sum = 0.0;
    for (std::size_t i = 0; i < f.shadow.size(); ++i) {
        EXPECT_NEAR(f.shadow[i], f.beauty.rgba[4 * (i / 3) + i % 3], 1e-6);
        sum += f.shadow[i];
    }
    EXPECT_GT(sum, 10.0) << "the cloud is lit and in view";
}

TEST(Passes, EmissionAloneMatchesTheAnalyticSlabAndAddsToTheLight)
{
    // Light off: C = (eta / sigma_t)(1 - exp(-sigma_t L)), L = 40 voxels, sigma_t = 0.05.
    const GridSource slab = slabGrid();
    RenderSettings dark = absorberSettings(0.05);
    dark.lights[0].color = Vec3d(0.0);
    dark.medium.emission = Vec3d(0.02, 0.01, 0.0);
    const Frame f = Renderer(dark).renderFrame(slab, slabCamera(), allFlatPasses());
    for (std::size_t i = 0; i < 64; ++i)
        for (int c = 0; c < 3; ++c) {
            const double expected = dark.medium.emission[c] / 0.05 * (1.0 - std::exp(-0.05 * 40.0));
            EXPECT_NEAR(f.beauty.rgba[4 * i + c], expected, 0.01 * expected + 1e-7);
            EXPECT_FLOAT_EQ(f.emission[3 * i + c], f.beauty.rgba[4 * i + c]);
        }
    // Lit and emitting: beauty = beauty of the light alone + the emission pass.
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    const Camera camera = cloudCamera(cloud, 96, 64);
    RenderSettings lit;
    RenderSettings both = lit;
    both.medium.emission = Vec3d(0.3, 0.1, 0.05);
    const Frame a = Renderer(lit).renderFrame(cloud, camera, allFlatPasses());
    const Frame b = Renderer(both).renderFrame(cloud, camera, allFlatPasses());
    double emitted = 0.0;
    for (std::size_t i = 0; i < b.emission.size(); ++i) {
        EXPECT_NEAR(b.beauty.rgba[4 * (i / 3) + i % 3], a.beauty.rgba[4 * (i / 3) + i % 3] + b.emission[i], 2e-6);
        emitted += b.emission[i];
    }
    EXPECT_GT(emitted, 1.0);
    // The reference integrator carries the same emission term (light off: emission alone).
    RenderSettings glow = both;
    glow.lights[0].color = Vec3d(0.0);
    RenderSettings ref = glow;
    ref.method = Method::RayMarch;
    ref.step = 0.5;
    const Image splatted = Renderer(glow).render(cloud, camera), marched = Renderer(ref).render(cloud, camera);
    float peak = 0.0f;
    for (std::size_t i = 0; i < marched.rgba.size(); i += 4) peak = std::max(peak, marched.rgba[i]);
    EXPECT_GT(peak, 0.05f);
    EXPECT_LT(rmse(splatted, marched, 0), 0.03 * peak);
}

TEST(Passes, PassesLeaveTheBeautyBitIdentical)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    const Camera camera = cloudCamera(cloud, 96, 64);
    for (const Vec3d& light : {Vec3d(0.7), Vec3d(1.0, 0.5, 0.2)}) { // grey and three-channel paths
        RenderSettings s;
        s.lights[0].color = light;
        const Image plain = Renderer(s).render(cloud, camera);
        PassRequest all = allFlatPasses();
        const Frame f = Renderer(s).renderFrame(cloud, camera, all);
        ASSERT_EQ(plain.rgba.size(), f.beauty.rgba.size());
        EXPECT_EQ(std::memcmp(plain.rgba.data(), f.beauty.rgba.data(), plain.rgba.size() * sizeof(float)), 0);
        // A deep image is composited at one sample a pixel (its samples have no average of
        // sub-pixels: docs/equations.md#sub-pixel-samples): --supersample 1's beauty.
        RenderSettings one = s;
        one.splat.supersample = 1;
        const Image plainOne = Renderer(one).render(cloud, camera);
        all.deep = true;
        const Frame d = Renderer(s).renderFrame(cloud, camera, all);
        EXPECT_EQ(std::memcmp(plainOne.rgba.data(), d.beauty.rgba.data(), plainOne.rgba.size() * sizeof(float)), 0);
    }
}

TEST(Passes, DeepSamplesAreTidyAndFlattenToTheBeauty)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    const Camera camera = cloudCamera(cloud, 96, 64);
    PassRequest deepOnly;
    deepOnly.deep = true;
    for (const double slab : {0.5, 2.0}) {
        RenderSettings s;
        s.splat.slab = slab;
        const Frame f = Renderer(s).renderFrame(cloud, camera, deepOnly);
        const DeepImage& d = f.deep;
        ASSERT_EQ(d.offsets.size(), 96u * 64u + 1u);
        double worst = 0.0;
        std::uint64_t maxSamples = 0;
        for (int y = 0; y < 64; ++y)
            for (int x = 0; x < 96; ++x) {
                const std::array<double, 4> flat = flatten(d, x, y);
                for (int c = 0; c < 4; ++c) worst = std::max(worst, std::abs(flat[std::size_t(c)] - f.beauty.pixel(x, y)[c]));
                const std::size_t i = std::size_t(y) * 96 + std::size_t(x);
                maxSamples = std::max(maxSamples, d.sampleCount(x, y));
                for (std::uint64_t k = d.offsets[i]; k < d.offsets[i + 1]; ++k) {
                    EXPECT_LT(d.samples[k].z, d.samples[k].zBack);
                    if (k > d.offsets[i]) {
                        EXPECT_LE(d.samples[k - 1].zBack, d.samples[k].z * (1.0f + 1e-6f));
                    }
                    EXPECT_GE(d.samples[k].a, 0.0f); // 0 where tau < 6e-8 (below float resolution)
                }
                if (f.beauty.pixel(x, y)[3] > 1e-3f) {
                    EXPECT_GT(d.sampleCount(x, y), 0u);
                }
            }
        EXPECT_LT(worst, 1e-4) << "--slab " << slab;
        EXPECT_GT(maxSamples, 3u);
    }
}

// A fog --iso surface (composited at its depth by the slab compositor) is in every pass: Z at
// the surface, no transmittance through it, a deep point sample at its depth (the samples in
// order, flattening to the beauty), and in the shadow pass the light's transmittance at it,
// which for a white surface lit head-on is the beauty.
TEST(Passes, IsoSurfaceIsInEveryPass)
{
    // A fog ball of radius 1: density 0.5 inside, a linear ramp 4 voxels wide, 0.25 on the sphere.
    const GridSource ball = gridSourceFromOpenVDB(makeFogAround([](const Vec3d& p) { return glm::length(p) - 1.0; }, 0.5, 25, 0.05));
    const Camera camera(orthoDownZ(0.0, 0.0, 5.0, 2.4, 48), Vec3d(0.0)); // the sphere's top at depth 4
    RenderSettings s;
    s.surface.iso = 0.25;
    s.medium.absorb = Vec3d(0.0); // albedo 1, white light from the camera: the shadow pass is the beauty
    s.lights[0].color = Vec3d(1.0);
    s.lights[0].direction = Vec3d(0.0, 0.0, 1.0);
    PassRequest all = allFlatPasses();
    all.deep = true;
    const Frame f = Renderer(s).renderFrame(ball, camera, all);
    const int x = 24, y = 24;
    const std::size_t i = std::size_t(y) * 48 + std::size_t(x);
    EXPECT_GT(f.beauty.pixel(x, y)[3], 0.999f) << "the surface is opaque";
    EXPECT_NEAR(f.depth[i], 4.0, 0.01) << "Z is the surface's";
    for (int c = 0; c < 3; ++c) {
        EXPECT_LT(f.transmittance[3 * i + std::size_t(c)], 1e-3f);
        EXPECT_NEAR(f.shadow[3 * i + std::size_t(c)], f.beauty.pixel(x, y)[c], 2e-3) << "channel " << c;
    }
    EXPECT_GT(f.beauty.pixel(x, y)[0], 0.1f) << "lit";
    const DeepImage& d = f.deep;
    bool surfaceSample = false;
    double worst = 0.0;
    for (int py = 0; py < 48; ++py)
        for (int px = 0; px < 48; ++px) {
            const std::size_t j = std::size_t(py) * 48 + std::size_t(px);
            for (std::uint64_t k = d.offsets[j]; k < d.offsets[j + 1]; ++k) {
                EXPECT_LE(d.samples[k].z, d.samples[k].zBack);
                if (k > d.offsets[j]) {
                    EXPECT_LE(d.samples[k - 1].zBack, d.samples[k].z * (1.0f + 1e-6f));
                }
            }
            const std::array<double, 4> flat = flatten(d, px, py);
            for (int c = 0; c < 4; ++c) worst = std::max(worst, std::abs(flat[std::size_t(c)] - f.beauty.pixel(px, py)[c]));
        }
    for (std::uint64_t k = d.offsets[i]; k < d.offsets[i + 1]; ++k) {
        surfaceSample = surfaceSample || (d.samples[k].z == d.samples[k].zBack && std::abs(d.samples[k].z - 4.0f) < 0.06f && d.samples[k].a > 0.99f);
    }
    EXPECT_TRUE(surfaceSample) << "a point sample at the surface, within half a slab";
    EXPECT_LT(worst, 1e-4);
}

TEST(Passes, RayMarchRejectsPassesItCannotMake)
{
    const GridSource slab = slabGrid();
    RenderSettings s = absorberSettings(0.1);
    s.method = Method::RayMarch;
    PassRequest shadow;
    shadow.shadow = true;
    EXPECT_THROW(Renderer(s).renderFrame(slab, slabCamera(), shadow), ValueError);
    RenderSettings bad;
    bad.medium.absorb = bad.medium.scatter = Vec3d(0.0);
    bad.medium.emission = Vec3d(1.0);
    EXPECT_THROW(Renderer{bad}, ValueError) << "emission without extinction";
}
