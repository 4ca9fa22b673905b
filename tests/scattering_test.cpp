/// @file scattering_test.cpp
/// @brief Issue 56's light: the Henyey-Greenstein phase and the octaves of multiple scattering
///        against the closed form of single scattering in a uniform slab lit from behind (the
///        raymarch reference absolutely, the splatter's scalar and SIMD backends as ratios to
///        their isotropic image), point lights weighed per sample, and the path-traced truth:
///        single scattering equal to the raymarch at gain 0, a white furnace, and a
///        non-absorbing slab reflecting what it does not transmit.
#include "fixtures.h"

#include "shading/shading.h"

#include <vdb_ewa/error.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

constexpr double kPi = 3.14159265358979323846;

/// A slab of density 1, 8 voxels thick (z in [0, 7]) and wide in x and y, voxels of @a h.
openvdb::FloatGrid::Ptr slab(int halfWidth, int thickness, double h)
{
    return makeBoxGrid(openvdb::Coord(-halfWidth, -halfWidth, 0), openvdb::Coord(halfWidth, halfWidth, thickness - 1), 1.0f, h);
}

/// A white scatterer of extinction @a sigma lit by one white light from direction @a towards,
/// physical shadows, no cutoff, fine steps.
RenderSettings whiteScatterer(double sigma, const Vec3d& towards)
{
    RenderSettings s;
    s.medium.absorb = Vec3d(0.0);
    s.medium.scatter = Vec3d(sigma);
    s.lights[0].direction = towards;
    s.lights[0].color = Vec3d(1.0);
    s.shadow.gain = 0.0;
    s.cutoff = 0.0;
    s.shadow.step = 0.1;
    s.shadow.resolution = 0.5;
    s.step = 0.1;
    return s;
}

/// Single scattering (and its octaves) of a laterally uniform slab of optical depth @a tau seen
/// straight through, lit by a unit light whose path through the slab is @a stretch times the
/// view's: the integral over the slab of e^(-K) x light, K the optical depth in front, whatever
/// the profile (dK = k du): sum_i a^i p_i (e^-tau - e^(-stretch b^i tau)) / (stretch b^i - 1).
double slabClosedForm(double tau, double stretch, double cosTheta, const Scattering& scattering)
{
    const detail::ScatteringOctaves octaves(scattering);
    double sum = 0.0;
    for (int i = 0; i < octaves.count(); ++i) {
        const double a = stretch * octaves.extinction(i);
        const double integral = std::abs(a - 1.0) < 1e-9 ? tau * std::exp(-tau) : (std::exp(-tau) - std::exp(-a * tau)) / (a - 1.0);
        sum += octaves.weight(i, cosTheta) * integral;
    }
    return sum;
}

double centre(const Image& image, int c = 0) { return image.pixel(image.width / 2, image.height / 2)[c]; }

double channelSum(const Image& image, int c)
{
    double s = 0.0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) s += image.pixel(x, y)[c];
    return s;
}

/// The slab lit from behind: light 40 degrees off the view axis, below the slab; the camera
/// looks down -z.
struct BackLitSlab
{
    double h = 0.1, sigma = 0.05; // 8 voxels: tau 0.4
    int thickness = 8;
    Vec3d towards{std::sin(40.0 * kPi / 180.0), 0.0, -std::cos(40.0 * kPi / 180.0)};
    openvdb::FloatGrid::Ptr grid = slab(40, thickness, h);
    CameraSettings camera = orthoDownZ(0.0, 0.0, 5.0, 1.0, 16);

    double tau() const { return sigma * thickness; }
    double stretch() const { return 1.0 / std::abs(towards.z); }
    double cosTheta() const { return glm::dot(towards, Vec3d(0.0, 0.0, -1.0)); }
};

} // namespace

TEST(Scattering, AThinSlabLitFromBehindMatchesTheClosedFormWithItsPhase)
{
    const BackLitSlab slab;
    struct Case
    {
        double g;
        int octaves;
    };
    for (const Case k : {Case{0.0, 1}, Case{0.6, 1}, Case{-0.4, 1}, Case{0.8, 4}}) {
        RenderSettings s = whiteScatterer(slab.sigma, slab.towards);
        s.scattering.anisotropy = k.g;
        s.scattering.octaves = k.octaves;
        const double expected = slabClosedForm(slab.tau(), slab.stretch(), slab.cosTheta(), s.scattering);
        s.method = Method::RayMarch;
        const double reference = centre(renderGrid(slab.grid, slab.camera, s));
        EXPECT_NEAR(reference / expected, 1.0, 0.01) << "raymarch, g " << k.g << ", octaves " << k.octaves;
    }
}

TEST(Scattering, TheSplatterWeighsEachLightByItsPhaseAndOctaves)
{
    // A directional light's scattering angle is the same along the ray: the splatter's image
    // at g over its isotropic one is the phase exactly; with octaves, the closed forms' ratio
    // (the light map's interpolation the same in both).
    const BackLitSlab slab;
    for (const bool simd : {false, true}) {
        RenderSettings iso = whiteScatterer(slab.sigma, slab.towards);
        iso.simd = simd;
        const double isotropic = centre(renderGrid(slab.grid, slab.camera, iso));
        ASSERT_GT(isotropic, 0.0);
        EXPECT_NEAR(isotropic / slabClosedForm(slab.tau(), slab.stretch(), slab.cosTheta(), iso.scattering), 1.0, 0.03);
        for (const double g : {0.6, -0.4}) {
            RenderSettings s = iso;
            s.scattering.anisotropy = g;
            EXPECT_NEAR(centre(renderGrid(slab.grid, slab.camera, s)) / isotropic, detail::henyeyGreenstein(slab.cosTheta(), g), 1e-4)
                << "simd " << simd << ", g " << g;
        }
        RenderSettings s = iso;
        s.scattering.anisotropy = 0.8;
        s.scattering.octaves = 4;
        const double ratio = slabClosedForm(slab.tau(), slab.stretch(), slab.cosTheta(), s.scattering) /
                             slabClosedForm(slab.tau(), slab.stretch(), slab.cosTheta(), iso.scattering);
        EXPECT_NEAR(centre(renderGrid(slab.grid, slab.camera, s)) / isotropic / ratio, 1.0, 0.01) << "simd " << simd << ", octaves";
    }
}

TEST(Scattering, PointLightsWeighTheirPhaseAtEachSample)
{
    // A point light beside a fog ball: the angle changes along each ray. The splatter and the
    // raymarch reference agree at g = 0.7 as they do at g = 0 (the same light maps), and the
    // forward-scattering image differs from the isotropic one where it should.
    const auto ball = makeFogAround([](const Vec3d& p) { return glm::length(p) - 1.0; }, 1.0, 16, 0.1);
    RenderSettings s;
    s.medium.absorb = Vec3d(0.0);
    s.medium.scatter = Vec3d(0.3);
    s.lights.clear();
    PointLight light;
    light.position = Vec3d(0.5, 0.0, -2.5); // behind the ball, off the axis
    light.color = Vec3d(4.0);
    s.pointLights = {light};
    s.shadow.gain = 0.0;
    s.cutoff = 0.0;
    s.shadow.step = 0.25;
    s.step = 0.25;
    const CameraSettings camera = lookAtCamera(Vec3d(0.0, 0.0, 5.0), Vec3d(0.0), 24, 24);
    double ratio[2] = {0.0, 0.0};
    double brightness[2] = {0.0, 0.0};
    for (int k = 0; k < 2; ++k) {
        s.scattering.anisotropy = k == 0 ? 0.0 : 0.7;
        RenderSettings reference = s;
        reference.method = Method::RayMarch;
        reference.pixelSamples = 4;
        const double splat = channelSum(renderGrid(ball, camera, s), 0);
        const double march = channelSum(renderGrid(ball, camera, reference), 0);
        ASSERT_GT(march, 0.0);
        ratio[k] = splat / march;
        brightness[k] = march;
    }
    EXPECT_NEAR(ratio[1] / ratio[0], 1.0, 0.02);
    EXPECT_GT(brightness[1], 1.5 * brightness[0]); // seen against the light: forward scattering
    // The octaves of a point light: the SIMD backend's (a vector log and exp per octave) as the
    // scalar one's, and brighter than one octave.
    s.scattering.octaves = 3;
    RenderSettings scalar = s;
    scalar.simd = false;
    const Image simdImage = renderGrid(ball, camera, s), scalarImage = renderGrid(ball, camera, scalar);
    float peak = 0.0f;
    for (const float v : scalarImage.rgba) peak = std::max(peak, v);
    EXPECT_LT(maxAbsDiff(simdImage, scalarImage), 1e-5 * peak); // the backends' documented agreement
    EXPECT_GT(channelSum(scalarImage, 0), 1.2 * ratio[1] * brightness[1]);
}

TEST(Scattering, OutOfRangeOptionsAreRefused)
{
    const auto refused = [](const std::function<void(RenderSettings&)>& change, const std::string& option) {
        RenderSettings s;
        change(s);
        try {
            s.validate();
            ADD_FAILURE() << option << " accepted";
        } catch (const ValueError& e) {
            EXPECT_NE(std::string(e.what()).find(option), std::string::npos) << e.what();
        }
    };
    refused([](RenderSettings& s) { s.scattering.anisotropy = 1.0; }, "--anisotropy");
    refused([](RenderSettings& s) { s.scattering.anisotropy = std::nan(""); }, "--anisotropy");
    refused([](RenderSettings& s) { s.scattering.octaves = 0; }, "--multiple-scattering");
    refused([](RenderSettings& s) { s.scattering.octaves = 17; }, "--multiple-scattering");
    refused([](RenderSettings& s) { s.scattering.octaveScatter = 1.5; }, "--octave-scatter");
    refused([](RenderSettings& s) { s.scattering.octaveExtinction = -0.1; }, "--octave-extinction");
    refused([](RenderSettings& s) { s.scattering.octaveAnisotropy = std::nan(""); }, "--octave-anisotropy");
    refused([](RenderSettings& s) { s.bounces = -1; }, "--bounces");
    refused([](RenderSettings& s) { s.pathSamples = 0; }, "--samples");
}

TEST(PathTrace, SingleScatteringEqualsTheRaymarchAtGainZero)
{
    // --bounces 0: one scattering event, lit by next-event estimation; in expectation the
    // raymarch reference's image at gain 0 (its rays spread over the pixels as the paths are,
    // its shadow rays fine: vdb_render's march drops half a --shadowstep of optical depth,
    // 2.6 % of this image at 0.25 and 0.8 % at 0.04, where ratio tracking drops none).
    const auto ball = makeFogAround([](const Vec3d& p) { return glm::length(p) - 1.0; }, 1.0, 14, 0.1);
    RenderSettings s;
    s.medium.absorb = Vec3d(0.1, 0.2, 0.3);
    s.medium.scatter = Vec3d(0.6);
    s.lights[0].direction = Vec3d(1.0, 0.5, -1.0);
    s.lights[0].color = Vec3d(1.0, 0.8, 0.6);
    s.scattering.anisotropy = 0.5;
    s.shadow.gain = 0.0;
    s.cutoff = 0.0;
    s.shadow.step = 0.25;
    s.step = 0.1;
    const CameraSettings camera = lookAtCamera(Vec3d(0.0, 0.0, 5.0), Vec3d(0.0), 16, 16);
    RenderSettings march = s;
    march.method = Method::RayMarch;
    march.pixelSamples = 4;
    march.shadow.step = 0.04;
    RenderSettings path = s;
    path.method = Method::PathTrace;
    path.bounces = 0;
    path.pathSamples = 256;
    const Image a = renderGrid(ball, camera, march), b = renderGrid(ball, camera, path);
    RenderStats stats;
    path.scattering.octaves = 4;
    const Image octaves = renderGrid(ball, camera, path, &stats);
    EXPECT_EQ(rmse(octaves, b), 0.0); // the octaves approximate what the paths do
    ASSERT_EQ(stats.warnings.size(), 1u);
    EXPECT_NE(stats.warnings[0].find("--multiple-scattering changes nothing with --method pathtrace"), std::string::npos);
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(channelSum(b, c) / channelSum(a, c), 1.0, 0.015) << "channel " << c;
}

TEST(PathTrace, AWhiteFurnaceVanishes)
{
    // Albedo 1 under a uniform environment of radiance 1 (the ambient light) and no other
    // light: every path ends in the environment, so each pixel is its alpha, whatever the phase.
    // (512 paths: 0.992 and 1.003 here; the sanitized build's paths differ in the last bits and
    // gave 1.021 at 64. A path tracer without the ambient's transmittance gives 4.7.)
    const auto ball = makeFogAround([](const Vec3d& p) { return glm::length(p) - 1.0; }, 1.0, 14, 0.1);
    for (const double g : {0.0, 0.7}) {
        RenderSettings s;
        s.method = Method::PathTrace;
        s.medium.absorb = Vec3d(0.0);
        s.medium.scatter = Vec3d(0.4);
        s.lights.clear();
        s.ambient = Vec3d(1.0);
        s.scattering.anisotropy = g;
        s.cutoff = 0.0;
        s.bounces = 256;
        s.pathSamples = 512;
        const Image image = renderGrid(ball, lookAtCamera(Vec3d(0.0, 0.0, 5.0), Vec3d(0.0), 16, 16), s);
        const double alpha = channelSum(image, 3);
        ASSERT_GT(alpha, 10.0);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(channelSum(image, c) / alpha, 1.0, 0.03) << "g " << g << ", channel " << c;
    }
}

TEST(PathTrace, ANonAbsorbingSlabReflectsWhatItDoesNotTransmit)
{
    // A slab of optical depth 1, albedo 1, lit at normal incidence by a light of colour 1 (an
    // irradiance of 4 pi: vdb_ewa's lights fold the isotropic phase in). The light leaving it
    // on both sides, 2 pi int_0^1 (L_R + L_T) mu dmu, plus the beam's e^-tau, is what came
    // in; L(mu) seen by an orthographic camera at the slab's middle, the integral by
    // Gauss-Legendre in mu, the light above (reflected) or below (transmitted).
    const double h = 0.1, sigma = 0.25;
    const int thickness = 4;
    const auto grid = slab(140, thickness, h);
    const double nodes[4] = {0.0694318442029737, 0.3300094782075719, 0.6699905217924281, 0.9305681557970263};
    const double weights[4] = {0.1739274225687269, 0.3260725774312731, 0.3260725774312731, 0.1739274225687269};
    double flux = 0.0;
    for (int k = 0; k < 4; ++k) {
        const double mu = nodes[k], sine = std::sqrt(1.0 - mu * mu);
        CameraSettings camera;
        camera.projection = Projection::Orthographic;
        camera.width = camera.height = 4;
        camera.frame = 0.2;
        const Vec3d centre(0.0, 0.0, 0.5 * (thickness - 1) * h);
        camera.translate = centre + 3.0 * Vec3d(sine, 0.0, mu);
        camera.lookAt = centre;
        for (const double side : {1.0, -1.0}) {
            RenderSettings s = whiteScatterer(sigma, Vec3d(0.0, 0.0, side));
            s.method = Method::PathTrace;
            s.bounces = 64;
            s.pathSamples = 1024;
            const Image image = renderGrid(grid, camera, s);
            const double radiance = channelSum(image, 0) / double(image.width * image.height);
            flux += 2.0 * kPi * weights[k] * radiance * mu;
        }
    }
    const double incoming = 4.0 * kPi, tau = sigma * thickness;
    EXPECT_NEAR((flux + incoming * std::exp(-tau)) / incoming, 1.0, 0.02);
}

TEST(PathTrace, RefusesWhatItDoesNotRender)
{
    const auto ball = makeFogAround([](const Vec3d& p) { return glm::length(p) - 1.0; }, 1.0, 8, 0.1);
    const GridSource source = gridSourceFromOpenVDB(ball);
    RenderSettings s;
    s.method = Method::PathTrace;
    const Camera camera(lookAtCamera(Vec3d(0.0, 0.0, 5.0), Vec3d(0.0), 8, 8), source.worldCentre());
    PassRequest passes;
    passes.shadow = true;
    try {
        Renderer(s).renderFrame(source, camera, passes);
        ADD_FAILURE() << "a shadow pass from the path tracer";
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("--method pathtrace"), std::string::npos) << e.what();
    }
}
