/// @file add_volume_test.cpp
/// @brief Several volumes in one frame (GridSource::withAddedVolume, --add-volume): two
///        interpenetrating clouds in one sweep are their summed field, in the splatter and the
///        reference, where compositing one over the other is visibly wrong; another voxel size
///        keeps its optical depth per world unit; level sets are refused.
#include "fixtures.h"

#include "source/source.h"

#include <vdb_ewa/error.h>
#include <vdb_ewa/openvdb_grid.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

/// A ball of density @a peak and radius @a radius (world) centred at @a centre, voxel @a h.
openvdb::FloatGrid::Ptr ball(const Vec3d& centre, double radius, float peak, double h)
{
    const int n = int(std::ceil((glm::length(centre) + radius) / h)) + 2;
    return makeFogGrid(openvdb::Coord(-n), openvdb::Coord(n), [=](const openvdb::Coord& c) {
        const double r = glm::length(Vec3d(c.x(), c.y(), c.z()) * h - centre);
        return r < radius ? peak * float(1.0 - r / radius) : 0.0f;
    }, h);
}

/// Straight alpha "over": @a front over @a back, premultiplied colours.
Image over(const Image& front, const Image& back)
{
    Image out = front;
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x) {
            float* o = out.pixel(x, y);
            const float* f = front.pixel(x, y);
            const float* b = back.pixel(x, y);
            for (int c = 0; c < 4; ++c) o[c] = f[c] + (1.0f - f[3]) * b[c];
        }
    return out;
}

} // namespace

TEST(AddVolume, InterpenetratingCloudsInOneSweepAreTheSummedFieldWhereOverIsWrong)
{
    // Two balls overlapping by half, lit along the line joining them (the first shadows the
    // second). One sweep (withAddedVolume) renders the sum of both fields, in the splatter and in
    // the reference, exactly as the summed grid renders. Compositing separate renders one over
    // the other, in either order, is visibly wrong by the reference's own measure (RMSE 0.025 and
    // 0.057 against its image of the sum) and by the splatter's.
    const double h = 0.05;
    auto a = ball(Vec3d(-0.25, 0.0, 0.0), 0.45, 1.0f, h), b = ball(Vec3d(0.25, 0.0, 0.0), 0.45, 1.0f, h);
    auto sum = a->deepCopy();
    {
        auto acc = sum->getAccessor();
        for (auto it = b->cbeginValueOn(); it; ++it) acc.setValueOn(it.getCoord(), acc.getValue(it.getCoord()) + *it);
    }
    const GridSource sa = gridSourceFromOpenVDB(a), sb = gridSourceFromOpenVDB(b), summed = gridSourceFromOpenVDB(sum);
    const GridSource merged = sa.withAddedVolume(sb);
    EXPECT_EQ(merged.activeVoxelCount(), summed.activeVoxelCount());

    const Camera cam(lookAtCamera(Vec3d(0.0, 0.3, 3.0), Vec3d(0.0), 48, 40), merged.worldCentre());
    RenderSettings settings;
    settings.lights[0].direction = Vec3d(-1.0, 0.2, 0.0); // the first ball shadows the second
    RenderSettings reference = settings;
    reference.method = Method::RayMarch;
    reference.step = 0.25;
    for (const RenderSettings& s : {settings, reference}) {
        const Renderer renderer(s);
        const Image swept = renderer.render(merged, cam), truth = renderer.render(summed, cam);
        EXPECT_EQ(maxAbsDiff(swept, truth), 0.0f) << "one sweep is the summed field";
        const Image ia = renderer.render(sa, cam), ib = renderer.render(sb, cam);
        EXPECT_GT(rmse(over(ia, ib), truth), 0.02) << int(s.method);
        EXPECT_GT(rmse(over(ib, ia), truth), 0.02) << int(s.method);
    }
}

TEST(AddVolume, AnotherVoxelSizeKeepsItsOpticalDepthPerWorldUnit)
{
    // A box of density 0.5 per voxel of 0.05 added to a faint box far away of voxels 0.1: on the
    // coarser voxels it reads 1.0 per voxel, the same optical depth per world unit. Seen down
    // -z through 0.4 world units, alpha 1 - exp(-0.2 x 0.5 x 8) either way (without the scaling,
    // 1 - exp(-0.2 x 0.5 x 4): 0.33 against 0.55).
    auto coarse = makeBoxGrid(openvdb::Coord(20, 20, -2), openvdb::Coord(22, 22, 2), 0.01f, 0.1);
    auto fine = makeBoxGrid(openvdb::Coord(-6, -6, -4), openvdb::Coord(6, 6, 3), 0.5f, 0.05);
    const GridSource merged = gridSourceFromOpenVDB(coarse).withAddedVolume(gridSourceFromOpenVDB(fine));
    RenderSettings settings = absorberSettings(0.2);
    const CameraSettings down = orthoDownZ(0.0, 0.0, 3.0, 0.2, 8);
    const Image a = Renderer(settings).render(merged, Camera(down, Vec3d(0.0)));
    const Image b = Renderer(settings).render(gridSourceFromOpenVDB(fine), Camera(down, Vec3d(0.0)));
    const double expected = 1.0 - std::exp(-0.2 * 0.5 * 8.0);
    EXPECT_NEAR(a.pixel(4, 4)[3], expected, 0.01);
    EXPECT_NEAR(a.pixel(4, 4)[3], b.pixel(4, 4)[3], 0.01);
}

TEST(AddVolume, LevelSetsAreRefused)
{
    const GridSource fog = gridSourceFromOpenVDB(makeBoxGrid(openvdb::Coord(0), openvdb::Coord(3), 1.0f, 0.1));
    const GridSource surface = gridSourceFromOpenVDB(sphereLevelSet(0.3, 0.05));
    EXPECT_THROW(fog.withAddedVolume(surface), InputError);
    EXPECT_THROW(surface.withAddedVolume(fog), InputError);
}

TEST(AddVolume, EachVolumeMovesWithItsOwnVelocityAndOverlapsWithTheDensityWeightedMean)
{
    // Two balls overlapping at x = 0, one moving along +x at 2 world units per second, one still
    // (no velocity grid), on different voxels. The sum's velocity is the mover's where it is
    // alone, 0 where the still ball is alone, and rho_a v / (rho_a + rho_b) where they overlap,
    // whichever volume is the base (the mover's velocity grid is rotated into world space).
    // The mover's ball at (0, -0.3, 0) with stored velocities (0, 2, 0), turned by x -> -y, y -> x:
    // at (-0.3, 0, 0) in the world, moving along +x.
    auto a = ball(Vec3d(0.0, -0.3, 0.0), 0.4, 1.0f, 0.05), b = ball(Vec3d(0.3, 0.0, 0.0), 0.4, 0.5f, 0.04);
    auto v = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    v->setTransform(a->transform().copy());
    v->tree().topologyUnion(a->tree());
    v->tree().voxelizeActiveTiles();
    for (auto it = v->beginValueOn(); it; ++it) it.setValue(openvdb::Vec3s(0.0f, 2.0f, 0.0f));
    const Mat4d turn(glm::dvec4(0.0, -1.0, 0.0, 0.0), glm::dvec4(1.0, 0.0, 0.0, 0.0), glm::dvec4(0.0, 0.0, 1.0, 0.0), glm::dvec4(0.0, 0.0, 0.0, 1.0));
    const GridSource mover = withVelocityGrid(gridSourceFromOpenVDB(a), v).transformed(turn);
    const GridSource still = gridSourceFromOpenVDB(b);
    ASSERT_TRUE(mover.hasVelocityGrid());
    for (const GridSource& sum : {mover.withAddedVolume(still), still.withAddedVolume(mover)}) {
        ASSERT_TRUE(sum.hasVelocityGrid());
        detail::VelocitySampler sampler(sum.impl());
        const Vec3d alone = sampler.at(Vec3d(-0.55, 0.0, 0.0)), stillAlone = sampler.at(Vec3d(0.55, 0.0, 0.0));
        EXPECT_NEAR(alone.x, 2.0, 1e-4);
        EXPECT_NEAR(alone.y, 0.0, 1e-4);
        EXPECT_NEAR(glm::length(stillAlone), 0.0, 1e-6);
        // At x = 0: rho_a = 1 - 0.3 / 0.4 = 0.25 per 0.05 voxel, rho_b = 0.125 per 0.04 voxel, or 0.15625 per 0.05.
        // The sum's voxels lie at x = 0 in both grids; the base's voxel length sets the weights' unit.
        const double ra = 0.25 / 0.05, rb = 0.125 / 0.04; // per world unit
        EXPECT_NEAR(sampler.at(Vec3d(0.0, 0.0, 0.0)).x, 2.0 * ra / (ra + rb), 0.02);
    }
    // Without velocities the sum has none: a still frame.
    EXPECT_FALSE(gridSourceFromOpenVDB(a).withAddedVolume(still).hasVelocityGrid());
    EXPECT_FALSE(still.withAddedVolume(gridSourceFromOpenVDB(a)).hasVelocityGrid());
}

namespace {

/// Radiance leaving a uniform segment of optical depth @a tau per channel with source @a s per
/// voxel length and extinction @a sigma per voxel length: s / sigma (1 - exp(-tau)).
double segment(double s, double sigma, double tau) { return sigma > 0.0 ? s / sigma * (1.0 - std::exp(-tau)) : s * tau; }

} // namespace

TEST(AddVolume, VolumesWithMediaOfTheirOwnAddExtinctionsAndLightsEachByItsDensity)
{
    // Seen down -z at the centre: box A (the input, density 0.5, absorb 0.2, emission
    // (0, 0.05, 0.1)) and box B (density 0.3, absorb (0.1, 0.3, 0.5), scatter (0.5, 0.3, 0.1),
    // extinction 0.6 in every channel) fill the same 8 voxels; box C, 6 voxels behind a gap
    // (density 0.4, absorb 0.4, emission (0.3, 0.1, 0), an emission grid of 0.2 x the emission
    // colour (1, 0.5, 0.25)), behind them. A white ambient light of 0.8 is the only light.
    // Where A and B mix, the extinction is 0.5 x 0.2 + 0.3 x 0.6 and the source per voxel length
    // 0.5 eA + 0.8 x 0.3 sB; C's light comes through them: the closed form of two uniform
    // segments (the trilinear ramps at their ends keep each ratio). Both the splatter and the
    // reference match it; the sum with the input's medium everywhere is far from it.
    const double h = 0.1;
    const auto a = makeBoxGrid(openvdb::Coord(-4, -4, 0), openvdb::Coord(4, 4, 7), 0.5f, h);
    const auto b = makeBoxGrid(openvdb::Coord(-4, -4, 0), openvdb::Coord(4, 4, 7), 0.3f, h);
    const auto c = makeBoxGrid(openvdb::Coord(-4, -4, -16), openvdb::Coord(4, 4, -11), 0.4f, h);
    const auto flame = makeBoxGrid(openvdb::Coord(-4, -4, -16), openvdb::Coord(4, 4, -11), 0.2f, h);
    Medium mb, mc;
    mb.absorb = Vec3d(0.1, 0.3, 0.5);
    mb.scatter = Vec3d(0.5, 0.3, 0.1);
    mc.absorb = Vec3d(0.4);
    mc.scatter = Vec3d(0.0);
    mc.emission = Vec3d(0.3, 0.1, 0.0);
    const GridSource cSource = withEmissionGrid(gridSourceFromOpenVDB(c), flame);
    const GridSource mixed = gridSourceFromOpenVDB(a).withAddedVolume(gridSourceFromOpenVDB(b), mb).withAddedVolume(cSource, mc);
    RenderSettings settings = absorberSettings(0.2);
    settings.medium.emission = Vec3d(0.0, 0.05, 0.1);
    settings.lights.clear();
    settings.ambient = Vec3d(0.8);
    settings.gridEmission.color = Vec3d(1.0, 0.5, 0.25);
    RenderSettings reference = settings;
    reference.method = Method::RayMarch;
    reference.step = 0.1;
    const Camera cam(orthoDownZ(0.0, 0.0, 3.0, 0.4, 8), Vec3d(0.0));
    double expected[3];
    for (int ch = 0; ch < 3; ++ch) {
        const double sigmaAB = 0.5 * 0.2 + 0.3 * 0.6, sourceAB = 0.5 * settings.medium.emission[ch] + 0.8 * 0.3 * mb.scatter[ch];
        const double sigmaC = 0.4 * 0.4, sourceC = 0.4 * mc.emission[ch] + 0.2 * settings.gridEmission.color[ch];
        expected[ch] = segment(sourceAB, sigmaAB, sigmaAB * 8.0) + std::exp(-sigmaAB * 8.0) * segment(sourceC, sigmaC, sigmaC * 6.0);
    }
    for (const RenderSettings& s : {settings, reference}) {
        RenderStats stats;
        const Image image = Renderer(s).render(mixed, cam, &stats);
        for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(image.pixel(4, 4)[ch], expected[ch], 0.01 * expected[ch] + 1e-3) << int(s.method) << " channel " << ch;
        for (const std::string& w : stats.warnings) EXPECT_EQ(w.find("not in proportion"), std::string::npos) << w;
        // The same volumes summed with the input's medium miss it by far.
        const GridSource summed = gridSourceFromOpenVDB(a).withAddedVolume(gridSourceFromOpenVDB(b)).withAddedVolume(cSource);
        const Image wrong = Renderer(s).render(summed, cam);
        EXPECT_GT(std::abs(wrong.pixel(4, 4)[1] - expected[1]), 0.2 * expected[1]);
    }
}

TEST(AddVolume, AVolumeGivenTheInputsMediumRendersAsTheSum)
{
    // withAddedVolume(other, the render's medium) is the plain sum: the mixed albedo is the
    // medium's everywhere. Two interpenetrating balls lit by a light that makes the first
    // shadow the second, in the splatter and the reference.
    const double h = 0.05;
    auto a = ball(Vec3d(-0.25, 0.0, 0.0), 0.45, 1.0f, h), b = ball(Vec3d(0.25, 0.0, 0.0), 0.45, 1.0f, h);
    RenderSettings settings;
    settings.lights[0].direction = Vec3d(-1.0, 0.2, 0.0);
    settings.medium.absorb = Vec3d(0.1, 0.2, 0.3);
    settings.medium.scatter = Vec3d(1.5, 1.0, 0.5);
    settings.medium.emission = Vec3d(0.1, 0.0, 0.05);
    const GridSource sa = gridSourceFromOpenVDB(a), sb = gridSourceFromOpenVDB(b);
    const Camera cam(lookAtCamera(Vec3d(0.0, 0.3, 3.0), Vec3d(0.0), 48, 40), sa.worldCentre());
    RenderSettings reference = settings;
    reference.method = Method::RayMarch;
    reference.step = 0.25;
    for (const RenderSettings& s : {settings, reference}) {
        const Renderer renderer(s);
        RenderStats stats;
        const Image mixed = renderer.render(sa.withAddedVolume(sb, s.medium), cam, &stats), summed = renderer.render(sa.withAddedVolume(sb), cam);
        EXPECT_LT(rmse(mixed, summed), 2e-3) << int(s.method);
        EXPECT_GT(alphaSum(summed), 100.0);
        EXPECT_TRUE(stats.warnings.empty()) << stats.warnings.front();
    }
}

TEST(AddVolume, AnExtinctionOfAnotherHueIsRenderedChannelByChannel)
{
    // B absorbs red only: its extinction (0.6, 0, 0) is not in proportion to the input's grey
    // 0.2, which one light map cannot march. The frame is rendered once per channel, every
    // medium grey at that channel's coefficients, and assembled: each channel is the closed
    // form of its own extinction, 0.5 x 0.2 + 0.5 x sigma_B, with A's emission 0.1 per unit
    // density; alpha the mean of the channels'. (Taken grey at its mean, 0.2, green and blue
    // would be 0.20 instead of 0.28.) A deep image cannot be assembled: grey, and said.
    const auto a = makeBoxGrid(openvdb::Coord(-4, -4, 0), openvdb::Coord(4, 4, 7), 0.5f, 0.1);
    const auto b = makeBoxGrid(openvdb::Coord(-4, -4, 0), openvdb::Coord(4, 4, 7), 0.5f, 0.1);
    Medium red;
    red.absorb = Vec3d(0.6, 0.0, 0.0);
    red.scatter = Vec3d(0.0);
    const GridSource mixed = gridSourceFromOpenVDB(a).withAddedVolume(gridSourceFromOpenVDB(b), red);
    RenderSettings settings = absorberSettings(0.2);
    settings.medium.emission = Vec3d(0.1);
    const Camera cam(orthoDownZ(0.0, 0.0, 3.0, 0.4, 8), Vec3d(0.0));
    RenderSettings reference = settings;
    reference.method = Method::RayMarch;
    reference.step = 0.1;
    for (const RenderSettings& s : {settings, reference}) {
        RenderStats stats;
        const Image image = Renderer(s).render(mixed, cam, &stats);
        ASSERT_EQ(stats.warnings.size(), 1u);
        EXPECT_NE(stats.warnings[0].find("rendered once per channel"), std::string::npos) << stats.warnings[0];
        double alpha = 0.0;
        for (int c = 0; c < 3; ++c) {
            const double sigma = 0.5 * 0.2 + 0.5 * red.absorb[c];
            EXPECT_NEAR(image.pixel(4, 4)[c], 0.5 * 0.1 / sigma * (1.0 - std::exp(-sigma * 8.0)), 0.01 * 0.26) << int(s.method) << " channel " << c;
            alpha += (1.0 - std::exp(-sigma * 8.0)) / 3.0;
        }
        EXPECT_NEAR(image.pixel(4, 4)[3], alpha, 0.01) << int(s.method);
    }
    PassRequest deep;
    deep.deep = true;
    RenderStats stats;
    Renderer(settings).renderFrame(mixed, cam, deep, &stats);
    ASSERT_FALSE(stats.warnings.empty());
    EXPECT_NE(stats.warnings[0].find("not in proportion"), std::string::npos) << stats.warnings[0];
    Medium negative;
    negative.absorb = Vec3d(-1.0);
    EXPECT_THROW(gridSourceFromOpenVDB(a).withAddedVolume(gridSourceFromOpenVDB(b), negative), ValueError);
}
