/// @file grid_emission_test.cpp
/// @brief Emission grids and blackbody temperature grids against closed forms, for the splatter
///        and the reference integrator.
#include "fixtures.h"

#include "shading/shading.h"

#include <vdb_ewa/error.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

constexpr int kDepth = 12;
constexpr double kH = 0.1;
constexpr double kPi = 3.14159265358979323846;

/// 40 x 40 x kDepth voxels of @a value centred on the origin in x, y; z in [0, kDepth), shifted
/// by @a dx voxels in x.
openvdb::FloatGrid::Ptr box(float value, int dx = 0, double h = kH, int scale = 1)
{
    return makeBoxGrid(openvdb::Coord(-20 / scale + dx, -20 / scale, 0), openvdb::Coord(19 / scale + dx, 19 / scale, kDepth / scale - 1), value, h);
}

/// No light, no cutoff: only what the grids emit.
RenderSettings emissionOnly(Method method)
{
    RenderSettings s;
    s.method = method;
    s.lights.clear();
    s.cutoff = 0.0;
    s.step = 0.25;
    return s;
}

Image render(const GridSource& source, const RenderSettings& settings)
{
    // 1.6 pixels a voxel: the frame's own pixels, whose low-pass filter smooths the kernel
    // lattice's ripple; 2 x 2 sub-pixels (--supersample) would show it, 1-3 % on a uniform
    // field (Renderer.UniformSlabTransmittanceIsExpMinusTau measures it): the emission's closed
    // forms are checked here.
    RenderSettings s = settings;
    s.splat.supersample = 1;
    return Renderer(s).render(source, Camera(orthoDownZ(-0.05, -0.05, 10.0, 1.0, 16), source.worldCentre()));
}

/// Every pixel's R, G, B within @a relative of @a expected.
void expectEveryPixel(const Image& img, const Vec3d& expected, double relative, const std::string& what)
{
    for (int j = 0; j < img.height; ++j)
        for (int i = 0; i < img.width; ++i)
            for (int c = 0; c < 3; ++c) {
                ASSERT_NEAR(img.pixel(i, j)[c], expected[c], relative * expected[c]) << what << " pixel " << i << "," << j << " c " << c;
            }
}

} // namespace

TEST(GridEmission, EmissionInsideADensitySlabMatchesTheClosedForm)
{
    // Emission e per voxel length inside absorbing density rho: C = e / sigma_t rho (1 - exp(-tau)).
    const double rho = 0.5, value = 0.8;
    for (const Method method : {Method::Splat, Method::RayMarch}) {
        RenderSettings s = emissionOnly(method);
        s.medium.absorb = Vec3d(0.05, 0.1, 0.2);
        s.medium.scatter = Vec3d(0.1);
        s.gridEmission.color = Vec3d(1.0, 0.5, 0.25);
        s.gridEmission.intensity = 2.0;
        const GridSource source = withEmissionGrid(gridSourceFromOpenVDB(box(float(rho))), box(float(value)));
        Vec3d expected;
        for (int c = 0; c < 3; ++c) {
            const double sigma = s.medium.absorb[c] + s.medium.scatter[c];
            const double e = value * s.gridEmission.color[c] * s.gridEmission.intensity;
            expected[c] = e / (sigma * rho) * (1.0 - std::exp(-sigma * rho * kDepth));
        }
        expectEveryPixel(render(source, s), expected, 0.01, method == Method::Splat ? "splat" : "raymarch");
    }
}

TEST(GridEmission, EmitsWhereThereIsNoDensity)
{
    // The density lies beside the view: the emission grid alone, C = e D, alpha 0. Also with the
    // emission grid at half the resolution (resampled onto the density's voxels).
    const double value = 0.3;
    for (const Method method : {Method::Splat, Method::RayMarch}) {
        for (const int scale : {1, 2}) {
            RenderSettings s = emissionOnly(method);
            s.gridEmission.color = Vec3d(0.2, 0.4, 1.0);
            const GridSource source = withEmissionGrid(gridSourceFromOpenVDB(box(1.0f, 200)), box(float(value), 0, kH * scale, scale));
            const Image img = render(source, s);
            const std::string what = std::string(method == Method::Splat ? "splat" : "raymarch") + (scale == 2 ? ", resampled" : "");
            expectEveryPixel(img, value * kDepth * s.gridEmission.color, 0.01, what);
            for (int j = 0; j < img.height; ++j)
                for (int i = 0; i < img.width; ++i) ASSERT_EQ(img.pixel(i, j)[3], 0.0f) << what;
        }
    }
}

TEST(GridEmission, BlackbodyOfAUniformTemperatureIsPlancksColourAndStefanBoltzmannsRadiance)
{
    // 3000 K everywhere in a slab of kDepth voxels with no density: C = L(T) x colour x D,
    // L = 1e-6 sigma T^4 / pi (Blender's unit), the colour of luminance 1 in linear Rec.709; its
    // chromaticity back in CIE xy is the Planckian locus's at 3000 K (NREL Radiance
    // blackbody.cal: 0.4369393, 0.4040768). D: the trilinear temperature falls to 0 K over the
    // voxel beyond each face, which adds the integral of (1 - u)^4 there: D = kDepth - 1 + 2/5,
    // slightly redder, for the reference (which samples T along the ray) and the splatter
    // (whose kernels carry each voxel's mean blackbody); T^4 of the voxel values would give
    // kDepth, 5 % more.
    const double sigma = 5.670374419e-8, kelvin = 3000.0;
    const double luminance = 1e-6 * sigma * std::pow(kelvin, 4) / kPi;
    const Vec3d colour = detail::xyzToLinearRec709(detail::blackbodyXyz(kelvin));
    for (const Method method : {Method::Splat, Method::RayMarch}) {
        RenderSettings s = emissionOnly(method);
        s.gridEmission.kelvinScale = 1000.0; // Blender's convention: the grid's value x the node's Temperature
        const GridSource source = withTemperatureGrid(gridSourceFromOpenVDB(box(1.0f, 200)), box(3.0f));
        const Image img = render(source, s);
        const std::string what = method == Method::Splat ? "splat" : "raymarch";
        expectEveryPixel(img, luminance * (kDepth - 1 + 0.4) * colour, 0.025, what);
        const float* px = img.pixel(8, 8);
        const Vec3d xyz = glm::inverse(detail::kXyzToLinearRec709) * Vec3d(px[0], px[1], px[2]);
        const double xyTolerance = 3e-3;
        EXPECT_NEAR(xyz.x / (xyz.x + xyz.y + xyz.z), 0.4369393, xyTolerance) << what;
        EXPECT_NEAR(xyz.y / (xyz.x + xyz.y + xyz.z), 0.4040768, xyTolerance) << what;
        // Twice the intensity, twice the light; hotter, bluer.
        s.gridEmission.blackbodyIntensity = 2.0;
        EXPECT_NEAR(render(source, s).pixel(8, 8)[1], 2.0 * px[1], 1e-4 * px[1]) << what;
        s.gridEmission.blackbodyIntensity = 1.0;
        s.gridEmission.kelvinScale = 2000.0;
        const Image hotter = render(source, s);
        const float* hot = hotter.pixel(8, 8);
        EXPECT_GT(hot[2] / hot[0], 2.0 * px[2] / px[0]) << what;
    }
}

TEST(GridEmission, EmptySpaceStaysDarkWhateverTheOffset)
{
    // Houdini's mapping puts value 0 at T0 (--temperature-offset): the grid's background reads
    // 0, yet only the cells touching its active voxels glow, in both integrators. A gap of
    // inactive voxels through the temperature slab stays dark.
    for (const Method method : {Method::Splat, Method::RayMarch}) {
        RenderSettings s = emissionOnly(method);
        s.gridEmission.kelvinOffset = 1500.0;
        s.gridEmission.kelvinScale = 1000.0;
        auto temperature = box(1.0f);
        temperature->tree().fill(openvdb::CoordBBox(openvdb::Coord(-6, -20, 0), openvdb::Coord(5, 19, kDepth - 1)), 0.0f, false);
        const GridSource source = withTemperatureGrid(gridSourceFromOpenVDB(box(1.0f, 200)), temperature);
        const Image img = Renderer(s).render(source, Camera(orthoDownZ(-0.05, -0.05, 10.0, 2.0, 24), source.worldCentre()));
        const std::string what = method == Method::Splat ? "splat" : "raymarch";
        EXPECT_GT(img.pixel(1, 12)[0], 1.0f) << what << ": the slab glows";
        for (int c = 0; c < 3; ++c) EXPECT_EQ(img.pixel(12, 12)[c], 0.0f) << what << ": the gap stays dark";
    }
}

TEST(GridEmission, RefusesWhatItCannotRender)
{
    const GridSource fog = gridSourceFromOpenVDB(box(1.0f));
    EXPECT_THROW(withEmissionGrid(fog, openvdb::Vec3SGrid::create()), InputError);
    EXPECT_THROW(withTemperatureGrid(fog, nullptr), InputError);
    EXPECT_THROW(fog.withEmissionGrid("flame"), InputError); // a host grid has no file
    const GridSource glowing = withEmissionGrid(fog, box(1.0f));
    RenderSettings s = emissionOnly(Method::RayMarchGaussian);
    EXPECT_THROW(render(glowing, s), ValueError);
    const GridSource sphere = withEmissionGrid(gridSourceFromOpenVDB(sphereLevelSet(1.0, 0.1)), box(1.0f));
    EXPECT_THROW(render(sphere, emissionOnly(Method::Splat)), ValueError);
}

namespace {

/// The middle 4 x 4 pixels' mean R, G, B of @a img.
Vec3d middle(const Image& img)
{
    Vec3d sum(0.0);
    for (int j = img.height / 2 - 2; j < img.height / 2 + 2; ++j)
        for (int i = img.width / 2 - 2; i < img.width / 2 + 2; ++i)
            for (int c = 0; c < 3; ++c) sum[c] += img.pixel(i, j)[c];
    return sum / 16.0;
}

/// A 16-pixel view 0.4 wide down z: the box's 0.1 voxels span 4 pixels, so --refine 4 refines.
Image renderClose(const GridSource& source, const RenderSettings& s, RenderStats* stats = nullptr)
{
    return Renderer(s).render(source, Camera(orthoDownZ(-0.05, -0.05, 10.0, 0.4, 16), source.worldCentre()), stats);
}

/// 2000 K (a temperature grid of 2, x 1000 K) in a box of density 10.
GridSource denseHotBox()
{
    return withTemperatureGrid(gridSourceFromOpenVDB(box(10.0f)), box(2.0f));
}

/// Emission only at vdb_render's extinction (16 optical depths a voxel of denseHotBox).
RenderSettings denseEmissionOnly(Method method)
{
    RenderSettings s = emissionOnly(method);
    s.medium.absorb = Vec3d(0.1);
    s.medium.scatter = Vec3d(1.5);
    s.gridEmission.kelvinScale = 1000.0;
    return s;
}

} // namespace

TEST(GridEmission, RefinedEmittersConvergeAtADenseHotFace)
{
    // 2000 K in a box of density 10 (16 optical depths a voxel). The light leaves from the
    // outer tenth of the top voxel, where the reference's trilinear temperature falls to 0 K
    // with the density still high: a voxel's kernel of its mean light is 5x too bright there.
    // --refine-emission samples the blackbody every 1/n voxel where the source function is steep
    // and the density thick (here: the faces, with the shell of light beyond), --refine where
    // the density's voxels are refined; both converge with n.
    const GridSource source = denseHotBox();
    RenderSettings s = denseEmissionOnly(Method::RayMarch);
    s.step = 0.125;
    const Vec3d reference = middle(renderClose(source, s));
    s.method = Method::Splat;
    s.splat.slab = 0.25;
    s.splat.lodPixels = 0.0;
    Vec3d previous(0.0);
    for (const int n : {1, 2, 4}) {
        s.splat.refineEmission = n;
        const Vec3d splat = middle(renderClose(source, s));
        for (int c = 0; c < 3; ++c) {
            const double ratio = splat[c] / reference[c];
            if (n > 1) {
                EXPECT_LT(ratio, previous[c]) << "n " << n << " c " << c << ": closer with each n";
            }
            previous[c] = ratio;
        }
        if (n == 1) {
            EXPECT_GT(previous[0], 4.0) << "unrefined: the mean light of the top voxel";
        }
    }
    // Red, most of the light: 5.4x, 1.7x, 1.07x the reference at n = 1, 2, 4.
    EXPECT_NEAR(previous[0], 1.0, 0.15) << "n = 4";
    // The density's refinement takes the emitters with it, to the same lattice: 2.0x, 1.43x at
    // --refine 2, 4 (the density's refined edge, a trilinear ramp, lets more of it out).
    s.splat.refineEmission = 1;
    s.splat.refine = 4;
    const double refined = middle(renderClose(source, s))[0] / reference[0];
    EXPECT_GT(refined, 1.0);
    EXPECT_LT(refined, 1.5) << "--refine 4";
}

TEST(GridEmission, RefinedEmittersOnlyWhereTheLightIsSteepAndTheDensityThick)
{
    // A uniform temperature in a thin density (0.2 optical depths a voxel): the faces' light
    // is steep but nothing hides it, so --refine-emission changes nothing, bit for bit. In the
    // dense box it does.
    RenderSettings s = emissionOnly(Method::Splat);
    s.gridEmission.kelvinScale = 1000.0;
    s.splat.lodPixels = 0.0;
    for (const float density : {0.125f, 10.0f}) {
        const GridSource source = withTemperatureGrid(gridSourceFromOpenVDB(box(density)), box(2.0f));
        s.splat.refineEmission = 1;
        const Image off = renderClose(source, s);
        s.splat.refineEmission = 2;
        const Image on = renderClose(source, s);
        const bool same = off.rgba == on.rgba;
        EXPECT_EQ(same, density < 1.0f) << "density " << density;
    }
}

TEST(GridEmission, RefinedEmittersAddUpWhereTheRefinementEnds)
{
    // A uniform 3000 K slab reaching 3 voxels above and below a density slab, with no
    // extinction: the image is the emission integrated along each ray whatever the density. The
    // refinement samples the density's voxels and their shell; the emitter kernels beyond stay.
    // Where the two meet, the samples carry the refined voxels' share of the trilinear partition
    // of unity (without it: 11 % more light; with it, 2-3 % less, at the refined lattice's edges).
    RenderSettings s = emissionOnly(Method::Splat);
    s.medium.absorb = Vec3d(0.0);
    s.medium.scatter = Vec3d(0.0);
    s.gridEmission.kelvinScale = 1000.0;
    s.splat.lodPixels = 0.0;
    auto density = makeBoxGrid(openvdb::Coord(-20, -20, 3), openvdb::Coord(19, 19, kDepth - 4), 2.0f, kH);
    const GridSource source = withTemperatureGrid(gridSourceFromOpenVDB(density), box(3.0f));
    s.splat.refineEmission = 1;
    RenderStats before, after;
    const Vec3d unrefined = middle(renderClose(source, s, &before));
    s.splat.refine = 4;
    const Vec3d refined = middle(renderClose(source, s, &after));
    EXPECT_GT(after.emitterKernels, 4 * before.emitterKernels) << "the emitters are refined";
    const double luminance = 1e-6 * 5.670374419e-8 * std::pow(3000.0, 4) / kPi;
    const Vec3d expected = luminance * (kDepth - 1 + 0.4) * detail::xyzToLinearRec709(detail::blackbodyXyz(3000.0));
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(unrefined[c], expected[c], 0.025 * expected[c]) << "c " << c;
        EXPECT_NEAR(refined[c], expected[c], 0.04 * expected[c]) << "c " << c;
    }
}

TEST(GridEmission, RefinedEmittersShrinkToTheirShareOfTheBudget)
{
    // The dense 2000 K box seen close: its faces' steep voxels and their cells would need about
    // 1 M kernels at n = 4 and 0.1 M at n = 2, past a quarter of 64 MiB (65 536 at 256 bytes).
    // The lattice is coarsened until the samples fit, with a warning, and the frame renders.
    const GridSource source = denseHotBox();
    RenderSettings s = denseEmissionOnly(Method::Splat);
    s.splat.refineEmission = 4;
    s.maxMemory = 64.0 * 1024 * 1024;
    RenderStats stats;
    const Image img = renderClose(source, s, &stats);
    bool warned = false;
    for (const std::string& w : stats.warnings) warned = warned || w.find("--refine-emission lowered") != std::string::npos;
    EXPECT_TRUE(warned);
    for (const float v : img.rgba) ASSERT_TRUE(std::isfinite(v));
    s.maxMemory = 8.0 * 1024 * 1024 * 1024;
    stats = RenderStats();
    renderClose(source, s, &stats);
    for (const std::string& w : stats.warnings) EXPECT_EQ(w.find("--refine-emission"), std::string::npos) << w;
}

TEST(GridEmission, RefinedEmissionGridsWhereTheLightLeavesTheDensity)
{
    // A uniform emission grid in the dense box goes as the density: its light falls to 0 across
    // the face's cell as the density does, the kernels are right (within 3 %) and nothing is
    // refined. An emission grid that stops a voxel below the top of a density of 1 (1.6 optical
    // depths a voxel) does not: its top voxels are refined, with the inactive voxels beyond
    // them (without those, the samples there carried the top voxel's tent twice). Red against
    // the reference: +4.3 % unrefined; +2.1 %, -4.2 % at --refine-emission 2, 4 (the density's
    // kernels keep their Gaussian edge); -1.7 %, +0.9 % with the density refined too (--refine),
    // which was +34 %, +61 % while the density's refined voxels left a hole beside kept ones.
    RenderSettings s = denseEmissionOnly(Method::RayMarch);
    s.step = 0.125;
    s.gridEmission.color = Vec3d(1.0, 0.5, 0.25);
    const GridSource goesAsDensity = withEmissionGrid(gridSourceFromOpenVDB(box(10.0f)), box(2.0f));
    const GridSource stopsBelow = withEmissionGrid(gridSourceFromOpenVDB(makeBoxGrid(openvdb::Coord(-20, -20, 0),
        openvdb::Coord(19, 19, kDepth), 1.0f, kH)), box(2.0f));
    const Vec3d reference[2] = {middle(renderClose(goesAsDensity, s)), middle(renderClose(stopsBelow, s))};
    s.method = Method::Splat;
    s.splat.slab = 0.25;
    s.splat.lodPixels = 0.0;
    std::uint64_t unrefinedKernels = 0;
    for (const int n : {1, 2, 4}) {
        s.splat.refineEmission = n;
        RenderStats stats;
        const Vec3d same = middle(renderClose(goesAsDensity, s, &stats));
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(same[c], reference[0][c], 0.03 * reference[0][c]) << "n " << n << " c " << c;
        if (n == 1) unrefinedKernels = stats.emitterKernels;
        EXPECT_EQ(stats.emitterKernels, unrefinedKernels) << "n " << n << ": nothing refined where the light goes as the density";
        RenderStats refined;
        const Vec3d emitters = middle(renderClose(stopsBelow, s, &refined));
        if (n > 1) {
            EXPECT_GT(refined.emitterKernels, 2 * unrefinedKernels) << "n " << n;
        }
        EXPECT_NEAR(emitters[0], reference[1][0], 0.05 * reference[1][0]) << "--refine-emission " << n;
        s.splat.refine = n;
        const Vec3d joint = middle(renderClose(stopsBelow, s));
        s.splat.refine = 1;
        EXPECT_NEAR(joint[0], reference[1][0], (n == 1 ? 0.05 : 0.02) * reference[1][0]) << "--refine " << n;
    }
}
