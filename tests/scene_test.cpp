/// @file scene_test.cpp
/// @brief A Scene's renders against cold ones: what it keeps (the light maps, with the rays
///        earlier renders marched) may never change a picture, and what a setting invalidates is
///        made anew (docs/api.md#scenes-what-a-render-reuses).
#include "fixtures.h"

#include <gtest/gtest.h>

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
