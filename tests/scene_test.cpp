/// @file scene_test.cpp
/// @brief A Scene's renders against cold ones: what it keeps (the light maps, with the rays
///        earlier renders marched) may never change a picture, and what a setting invalidates is
///        made anew (docs/api.md#scenes-what-a-render-reuses).
#include "coarse_image.h"
#include "fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

PassRequest somePasses()
{
    PassRequest passes;
    passes.transmittance = passes.shadow = true;
    return passes;
}

/// The same frame bit for bit: beauty and the passes asked for.
void expectSameFrame(const Frame& a, const Frame& b, const std::string& what)
{
    ASSERT_EQ(a.beauty.rgba.size(), b.beauty.rgba.size()) << what;
    std::size_t differ = 0;
    for (std::size_t i = 0; i < a.beauty.rgba.size(); ++i) differ += a.beauty.rgba[i] != b.beauty.rgba[i];
    EXPECT_EQ(differ, 0u) << what << ": beauty values that differ";
    EXPECT_TRUE(a.transmittance == b.transmittance) << what << ": the transmittance differs";
    EXPECT_TRUE(a.shadow == b.shadow) << what << ": the shadow pass differs";
}

Frame coldFrame(const GridSource& grid, const Camera& camera, const RenderSettings& settings, RenderStats* stats = nullptr)
{
    return Renderer(settings).renderFrame(grid, camera, somePasses(), stats);
}

} // namespace

// The camera moves and moves back: every frame is the cold render's, the light maps are kept
// from the first render on, and later renders march fewer rays than a cold one, none on the
// way back.
TEST(Scene, ACameraMoveRendersWhatAColdRenderDoes)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    const Camera cameras[] = {cloudCamera(cloud, 96, 72), Camera(lookAtCamera(Vec3d(0.3, 0.2, 1.2), Vec3d(0.0), 96, 72), cloud.worldCentre()),
        cloudCamera(cloud, 96, 72)};
    RenderSettings settings;
    settings.lights.resize(2);
    settings.lights[1].direction = Vec3d(-0.2, 0.4, 1.0);
    settings.lights[1].color = Vec3d(0.2, 0.4, 0.9);
    Scene scene(cloud, settings);
    for (int k = 0; k < 3; ++k) {
        RenderStats warm, cold;
        const Frame frame = scene.render(cameras[k], somePasses(), &warm);
        expectSameFrame(frame, coldFrame(cloud, cameras[k], settings, &cold), "camera " + std::to_string(k));
        EXPECT_TRUE(warm.streamed);
        EXPECT_EQ(warm.lightRays, cold.lightRays);
        if (k == 0) {
            // The frame's parts (sub-pixels fading in) share the maps: what the cold frame marches
            // twice, the scene's marches once and then reads.
            EXPECT_EQ(warm.lightRaysMarched + warm.lightRaysReused, cold.lightRaysMarched);
        } else {
            EXPECT_GE(warm.lightMapsReused, 2u);
            EXPECT_GT(warm.lightRaysReused, 0u);
            EXPECT_LT(warm.lightRaysMarched, cold.lightRaysMarched);
        }
        if (k == 2) {
            EXPECT_EQ(warm.lightRaysMarched, 0u) << "the way back reads rays marched already";
        }
        EXPECT_EQ(warm.warnings, cold.warnings);
    }
}

// Each class of setting, changed between two renders of a Scene: those the light maps read make
// them anew, the others keep them; the image is the cold render's with the new settings.
TEST(Scene, WhatASettingChangesIsMadeAnewAndNothingElse)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    const Camera first = cloudCamera(cloud, 80, 60);
    const Camera second(lookAtCamera(Vec3d(0.3, 0.2, 1.2), Vec3d(0.0), 80, 60), cloud.worldCentre());
    struct Change
    {
        const char* what;
        std::function<void(RenderSettings&)> apply;
        bool keepsLight;
    };
    const Change changes[] = {
        {"--light direction", [](RenderSettings& s) { s.lights[0].direction = Vec3d(-0.5, 0.7, 0.2); }, false},
        {"--light colour", [](RenderSettings& s) { s.lights[0].color = Vec3d(0.9, 0.5, 0.2); }, true},
        {"--light colour to black", [](RenderSettings& s) { s.lights[0].color = Vec3d(0.0); }, false},
        {"a second --light", [](RenderSettings& s) { s.lights.push_back(s.lights[0]); }, false},
        {"--absorb", [](RenderSettings& s) { s.medium.absorb = Vec3d(0.4); }, false},
        {"--scatter", [](RenderSettings& s) { s.medium.scatter = Vec3d(2.5, 2.0, 1.5); }, false},
        {"--shadowstep", [](RenderSettings& s) { s.shadow.step = 0.75; }, false},
        {"--shadow-res", [](RenderSettings& s) { s.shadow.resolution = 2.0; }, false},
        {"--gain", [](RenderSettings& s) { s.shadow.gain = 0.0; }, false},
        {"--cutoff", [](RenderSettings& s) { s.cutoff = 0.02; }, false},
        {"--max-memory", [](RenderSettings& s) { s.maxMemory = std::uint64_t(96) << 20; }, false},
        {"--ambient", [](RenderSettings& s) { s.ambient = Vec3d(0.1); }, true},
        {"--emission", [](RenderSettings& s) { s.medium.emission = Vec3d(0.1, 0.05, 0.0); }, true},
        {"--kernel-sigma", [](RenderSettings& s) { s.splat.kernelSigma = 0.6; }, true},
        {"--slab", [](RenderSettings& s) { s.splat.slab = 1.0; }, true},
        {"--simd off", [](RenderSettings& s) { s.simd = false; }, true},
        {"--cull off (the whole frame)", [](RenderSettings& s) { s.cull = false; }, true},
        {"--point-light", [](RenderSettings& s) { s.pointLights.push_back(PointLight{}); s.pointLights[0].position = Vec3d(0.0, 1.0, 0.5); }, false},
    };
    for (const Change& change : changes) {
        RenderSettings changed;
        change.apply(changed);
        Scene scene(cloud, RenderSettings{});
        scene.render(first, somePasses());
        scene.setSettings(changed);
        RenderStats warm;
        const Frame frame = scene.render(second, somePasses(), &warm);
        expectSameFrame(frame, coldFrame(cloud, second, changed), change.what);
        EXPECT_EQ(warm.lightMapsReused > 0, change.keepsLight) << change.what;
    }
}

// Point and spot lights' maps are kept too, and an --iso surface (the whole frame, which reads
// the maps at its kernels without asking for rays) gets every ray of a kept map marched first.
TEST(Scene, PointLightsAndAnIsoSurfaceReadKeptMapsAsFreshOnes)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    RenderSettings settings;
    settings.pointLights.resize(1);
    settings.pointLights[0].position = Vec3d(0.2, 0.9, 0.6);
    settings.pointLights[0].color = Vec3d(2.0, 1.5, 1.0);
    settings.surface.iso = 0.3;
    const Camera near(lookAtCamera(Vec3d(0.3, 0.2, 1.2), Vec3d(0.0), 80, 60), cloud.worldCentre());
    const Camera far = cloudCamera(cloud, 80, 60);
    Scene scene(cloud, settings);
    int k = 0;
    for (const Camera& camera : {near, far, near}) {
        RenderStats warm, cold;
        const Frame frame = scene.render(camera, somePasses(), &warm);
        expectSameFrame(frame, coldFrame(cloud, camera, settings, &cold), "render " + std::to_string(k));
        EXPECT_FALSE(warm.streamed);
        EXPECT_EQ(warm.lightMapsReused, k == 0 ? 0u : 2u);
        EXPECT_EQ(warm.lightRaysMarched + warm.lightRaysReused, cold.lightRaysMarched) << "every ray, as the cold whole frame";
        ++k;
    }
}

// A render cancelled while it marches light keeps nothing: the next render starts cold and is
// the cold render's image.
TEST(Scene, ACancelledRenderKeepsNothing)
{
    struct CancelHalfway : Interrupter
    {
        bool wasInterrupted(int percent) override { return percent >= 50; }
    };
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    const Camera camera = cloudCamera(cloud, 96, 72);
    RenderStats first;
    Scene(cloud, RenderSettings{}).render(camera, somePasses(), &first);
    ASSERT_GT(first.lightRaysMarched, 0u);
    Scene scene(cloud, RenderSettings{});
    CancelHalfway cancel;
    EXPECT_THROW(scene.render(camera, somePasses(), nullptr, &cancel), Cancelled);
    RenderStats warm;
    expectSameFrame(scene.render(camera, somePasses(), &warm), coldFrame(cloud, camera, RenderSettings{}), "after a cancel");
    EXPECT_EQ(warm.lightRaysMarched, first.lightRaysMarched) << "a scene's first render marches them all again";
    RenderStats again;
    scene.render(camera, somePasses(), &again);
    EXPECT_EQ(again.lightRaysMarched, 0u);
    scene.clear();
    scene.render(camera, somePasses(), &again);
    EXPECT_EQ(again.lightRaysMarched, first.lightRaysMarched) << "clear() lets go of the maps";
}

// Bad settings are refused when given, as a Renderer refuses them.
TEST(Scene, RefusesSettingsOutOfRange)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    RenderSettings bad;
    bad.shadow.step = -1.0;
    EXPECT_THROW(Scene(cloud, bad), ValueError);
    Scene scene(cloud, RenderSettings{});
    EXPECT_THROW(scene.setSettings(bad), ValueError);
    EXPECT_EQ(scene.settings().shadow.step, RenderSettings{}.shadow.step);
}

namespace {

/// The share of @a frame's pixels where alpha exceeds 0.05 both here and in @a other, of those
/// where it does in either (the silhouettes' intersection over union), and the mean |alpha
/// difference| over the mean alpha.
struct AlphaAgreement
{
    double silhouette = 0;
    double meanDifference = 0;
};

AlphaAgreement alphaAgreement(const Image& a, const Image& b)
{
    std::size_t both = 0, either = 0;
    double difference = 0, alpha = 0;
    for (std::size_t i = 3; i < a.rgba.size(); i += 4) {
        const bool inA = a.rgba[i] > 0.05f, inB = b.rgba[i] > 0.05f;
        both += inA && inB;
        either += inA || inB;
        difference += std::abs(double(a.rgba[i]) - double(b.rgba[i]));
        alpha += double(b.rgba[i]);
    }
    return {double(both) / double(std::max<std::size_t>(either, 1)), difference / std::max(alpha, 1e-30)};
}

/// The alpha-weighted mean pixel position.
Vec2d alphaCentroid(const Image& image)
{
    Vec2d sum(0.0);
    double weight = 0;
    for (int y = 0; y < image.height; ++y) {
        for (int x = 0; x < image.width; ++x) {
            const double a = image.rgba[(std::size_t(y) * std::size_t(image.width) + std::size_t(x)) * 4 + 3];
            sum += a * Vec2d(x + 0.5, y + 0.5);
            weight += a;
        }
    }
    return sum / std::max(weight, 1e-30);
}

/// Progress reports.
struct RecordingInterrupter : Interrupter
{
    std::vector<int> percents;
    bool wasInterrupted(int percent) override
    {
        percents.push_back(percent);
        return false;
    }
};

} // namespace

// A progressive render: a coarse image of the camera's size first, at a sixteenth of the
// footprint samples, close to the asked image; then the asked image, the one returned, which is
// the cold render's bit for bit. One rising progress runs over both.
TEST(Scene, AProgressiveRenderGivesACoarseImageThenTheAskedOne)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    const Camera camera = cloudCamera(cloud, 128, 96);
    PassRequest passes = somePasses();
    passes.deep = true;
    Scene scene(cloud, RenderSettings{});
    std::vector<Frame> images;
    std::vector<RenderStats> stats;
    std::vector<std::size_t> percentsBefore;
    RecordingInterrupter progress;
    RenderStats returnedStats;
    const Frame returned = scene.render(camera, RenderSettings{}, [&](const Frame& f, const RenderStats& s) {
        images.push_back(f);
        stats.push_back(s);
        percentsBefore.push_back(progress.percents.size());
    }, passes, &returnedStats, &progress);
    ASSERT_EQ(images.size(), 2u);
    EXPECT_EQ(stats[0].coarseScale, detail::kCoarseScale);
    EXPECT_EQ(stats[1].coarseScale, 1);
    EXPECT_EQ(returnedStats.coarseScale, 1);
    EXPECT_EQ(images[0].beauty.width, 128);
    EXPECT_EQ(images[0].beauty.height, 96);
    EXPECT_EQ(images[0].transmittance.size(), returned.transmittance.size());
    EXPECT_TRUE(images[0].deep.offsets.empty()) << "deep samples have no coarse image";
    EXPECT_FALSE(returned.deep.offsets.empty());
    EXPECT_LT(stats[0].slabComposites * 4, stats[1].slabComposites);
    expectSameFrame(images[1], returned, "the last image and the one returned");
    const Frame cold = Renderer(RenderSettings{}).renderFrame(cloud, camera, passes);
    expectSameFrame(returned, cold, "a progressive render's asked image");
    const AlphaAgreement agreement = alphaAgreement(images[0].beauty, returned.beauty);
    // Measured: silhouettes 0.89 alike, alpha 5 % apart on average, centroids 0.02 pixels apart
    // (the asked image against itself 2 pixels to the side: 0.93, 8 %).
    EXPECT_GT(agreement.silhouette, 0.85);
    EXPECT_LT(agreement.meanDifference, 0.1);
    const Vec2d c0 = alphaCentroid(images[0].beauty), c1 = alphaCentroid(returned.beauty);
    EXPECT_LT(std::hypot(c0.x - c1.x, c0.y - c1.y), 0.25) << "the coarse image is registered: " << c0.x << "," << c0.y << " against " << c1.x << "," << c1.y;
    ASSERT_GE(progress.percents.size(), 2u);
    EXPECT_TRUE(std::is_sorted(progress.percents.begin(), progress.percents.end()));
    for (std::size_t i = 0; i < percentsBefore[0]; ++i) EXPECT_LE(progress.percents[i], 10) << "the coarse image's share";
    EXPECT_EQ(progress.percents.back(), 100);
}

// An image under 2 x kCoarseSide pixels a side has no coarse image: the asked one comes at once.
TEST(Scene, AnImageTooSmallForACoarseOneGetsOnlyTheAskedOne)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    const Camera camera = cloudCamera(cloud, 40, 24);
    Scene scene(cloud, RenderSettings{});
    std::vector<int> scales;
    const Frame frame = scene.render(camera, RenderSettings{}, [&](const Frame&, const RenderStats& s) { scales.push_back(s.coarseScale); }, somePasses());
    EXPECT_EQ(scales, std::vector<int>{1});
    expectSameFrame(frame, coldFrame(cloud, camera, RenderSettings{}), "a small image");
}

// A cancel made while the coarse image is drawn stops the render before the asked image: the
// callback is not called again, and the scene renders the cold frame after it.
TEST(Scene, ACancelBetweenTheImagesStopsAtOnce)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    const Camera camera = cloudCamera(cloud, 128, 96);
    Scene scene(cloud, RenderSettings{});
    Interrupter interrupter;
    int calls = 0;
    EXPECT_THROW(scene.render(camera, RenderSettings{}, [&](const Frame&, const RenderStats&) {
        ++calls;
        interrupter.cancel(); // a viewport's view moved on
    }, somePasses(), nullptr, &interrupter), Cancelled);
    EXPECT_EQ(calls, 1);
    expectSameFrame(scene.render(camera, somePasses()), coldFrame(cloud, camera, RenderSettings{}), "after a cancel");
}

// Asked for with draft's light maps (--quality draft), the coarse image's maps are the asked
// image's: one set, marched once, the asked image reading what the coarse one marched.
TEST(Scene, ADraftSceneSharesOneSetOfLightMapsBetweenItsImages)
{
    const GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    const Camera camera = cloudCamera(cloud, 128, 96);
    const RenderSettings draft = RenderSettings::preset(Quality::Draft);
    ASSERT_TRUE(detail::coarseLightsAreAsked(draft));
    ASSERT_FALSE(detail::coarseLightsAreAsked(RenderSettings{}));
    Scene scene(cloud, draft);
    std::vector<RenderStats> stats;
    const Frame frame = scene.render(camera, draft, [&](const Frame&, const RenderStats& s) { stats.push_back(s); }, somePasses());
    ASSERT_EQ(stats.size(), 2u);
    EXPECT_GT(stats[0].lightRaysMarched, 0u);
    EXPECT_GE(stats[1].lightMapsReused, 1u) << "the asked image reads the maps the coarse one made";
    EXPECT_GT(stats[1].lightRaysReused, 0u);
    expectSameFrame(frame, coldFrame(cloud, camera, draft), "a draft scene's asked image");
}
