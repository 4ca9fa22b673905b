/// @file kernel_refinement_test.cpp
/// @brief --refine: the refined kernels' Gaussian sum against the trilinear field it samples
///        (mass kept, error falling as the lattice refines), and the image converging.
#include "fixtures.h"

#include "projection/projection.h"
#include "source/source.h"

#include "support/openvdb_tools.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

constexpr double kSigma = 0.5; // RenderSettings().splat.kernelSigma

/// The kernels of @a grid as the renderer builds them with --refine @a n (prefilter on).
detail::KernelSet kernelsOf(const GridSource& source, int n, bool prefilter = true)
{
    RenderSettings s;
    s.splat.lodPixels = 0.0;
    s.splat.tileKernelSpacing = 1;
    detail::KernelSet set = detail::extractKernels(source.impl(), s);
    const double alpha = prefilter ? detail::quasiInterpolationAlpha(kSigma) : 0.0;
    // A camera close enough that every voxel spans many pixels: every voxel is refined.
    CameraSettings cam;
    cam.translate = Vec3d(0.0, 0.0, 10.0);
    const detail::LevelOfDetail scale(source.impl(), Camera(cam, Vec3d(0.0)), s);
    openvdb::MaskGrid sampled(false);
    detail::refineKernels(source.impl(), n, alpha, float(s.cutoff), scale, set, sampled);
    if (alpha > 0.0) detail::quasiInterpolate(source.impl(), alpha, set, &sampled);
    return set;
}

/// The Gaussian sum sum_k w_k s_k^3 G(x - x_k), std. deviation kernelSigmaVoxels (Eq. 8, 19).
double gaussianSum(const detail::KernelSet& set, const Vec3d& x)
{
    double sum = 0.0;
    for (const detail::Kernel& k : set.kernels) {
        const double s = detail::kernelSigmaVoxels(k, kSigma), d2 = glm::dot(x - k.pIndex, x - k.pIndex);
        if (d2 > 49.0 * s * s) continue;
        const double mass = double(k.density) * double(k.spacing) * k.spacing * k.spacing;
        sum += mass * std::exp(-0.5 * d2 / (s * s)) / std::pow(2.0 * M_PI * s * s, 1.5);
    }
    return sum;
}

double trilinear(const GridSource& source, const Vec3d& x)
{
    return openvdb::tools::BoxSampler::sample(source.impl().field->tree(), openvdb::Vec3R(x.x, x.y, x.z));
}

/// A dense cube of 4^3 voxels whose values vary (3.4 down to 1): sharp faces, inner gradients.
GridSource denseCube()
{
    return gridSourceFromOpenVDB(makeFogGrid(openvdb::Coord(0), openvdb::Coord(3),
        [](const openvdb::Coord& c) { return float(1.0 + 0.3 * c.x() + 0.2 * c.y() + 0.1 * c.z() * c.z()); }, 1.0));
}

/// RMS of (Gaussian sum - trilinear field) over random points of the cube and one voxel beyond.
double rmsFieldError(const GridSource& source, const detail::KernelSet& set)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.5, 4.5);
    double sum = 0.0;
    const int samples = 400;
    for (int i = 0; i < samples; ++i) {
        const Vec3d x(u(rng), u(rng), u(rng));
        const double e = gaussianSum(set, x) - trilinear(source, x);
        sum += e * e;
    }
    return std::sqrt(sum / samples);
}

} // namespace

TEST(KernelRefinement, KeepsTheMass)
{
    // The fine samples' midpoint rule is exact on the trilinear pieces (even n: the fine cells
    // do not straddle the pieces' edges), and the prefilter moves no mass: sum w s^3 = sum v.
    const GridSource cube = denseCube();
    double values = 0.0;
    for (auto it = cube.impl().grid->cbeginValueOn(); it; ++it) values += *it;
    for (const int n : {2, 4}) {
        for (const bool prefilter : {false, true}) {
            const detail::KernelSet set = kernelsOf(cube, n, prefilter);
            double mass = 0.0;
            for (const detail::Kernel& k : set.kernels) {
                EXPECT_FLOAT_EQ(k.spacing, 1.0f / float(n));
                mass += double(k.density) * k.spacing * k.spacing * k.spacing;
            }
            EXPECT_NEAR(mass, values, 1e-4 * values) << "n " << n << " prefilter " << prefilter;
        }
    }
}

TEST(KernelRefinement, GaussianSumConvergesToTheTrilinearField)
{
    // The fine lattice holds the voxel centres, where the trilinear pieces meet: a lattice
    // offset by half a fine step (samples at +-1/4 voxel) missed those kinks and was worse
    // than no refinement (0.115 against 0.057). The error falls until the kernels' own ripple
    // (3.4 % at sigma = 0.5 lattice steps) is what is left (docs/numerics.md#refined-kernels).
    const GridSource cube = denseCube();
    const double e1 = rmsFieldError(cube, kernelsOf(cube, 1)), e2 = rmsFieldError(cube, kernelsOf(cube, 2)),
                 e4 = rmsFieldError(cube, kernelsOf(cube, 4));
    std::printf("RMS error of the Gaussian sum against the trilinear field: n 1 %.4f, 2 %.4f, 4 %.4f\n", e1, e2, e4);
    EXPECT_LT(e2, 0.5 * e1);
    EXPECT_LT(e4, e2);
}

TEST(KernelRefinement, SamplesBelowTheCutoffReadAsZero)
{
    // vdb_render and the reference skip field samples below --cutoff; so do the fine samples.
    // A dense voxel in a thin fringe (0.003 < cutoff 0.005): the fringe's own samples vanish.
    const GridSource grid = gridSourceFromOpenVDB(makeFogGrid(openvdb::Coord(-3), openvdb::Coord(3),
        [](const openvdb::Coord& c) { return c == openvdb::Coord(0) ? 1.0f : 0.003f; }, 1.0));
    const detail::KernelSet set = kernelsOf(grid, 2);
    ASSERT_GT(set.kernels.size(), 8u);
    for (const detail::Kernel& k : set.kernels) {
        if (k.density > 0.0f) {
            EXPECT_GE(trilinear(grid, k.pIndex), RenderSettings().cutoff) << k.pIndex.x << "," << k.pIndex.y << "," << k.pIndex.z;
        }
    }
}

TEST(KernelRefinement, OnlyWhereVoxelsSpanThePixelsAndTheFieldVaries)
{
    // Seen from far off (voxels of a fraction of a pixel) nothing is refined: there the refined
    // Gaussian sum only blurs what the pixel grid point-samples. Close up, a cube whose values
    // vary is refined with its one-voxel shell (18^3 voxels sampled); a uniform one only where
    // its voxels' neighbourhoods reach outside it (16^3 - 14^3 voxels, and the shell).
    const GridSource ramp = gridSourceFromOpenVDB(makeFogGrid(openvdb::Coord(0), openvdb::Coord(15),
        [](const openvdb::Coord& c) { return float(1.0 + 0.01 * (c.x() + c.y() + c.z())); }, 0.1));
    const GridSource uniform = gridSourceFromOpenVDB(makeBoxGrid(openvdb::Coord(0), openvdb::Coord(15), 1.0f, 0.1));
    RenderSettings s;
    s.splat.refine = 2;
    CameraSettings cam;
    cam.width = cam.height = 64;
    const auto refinedVoxels = [&](const GridSource& grid, double distance) {
        cam.translate = Vec3d(0.8, 0.8, distance);
        cam.lookAt = Vec3d(0.8, 0.8, 0.0);
        RenderStats stats;
        Renderer(s).render(grid, Camera(cam, grid.worldCentre()), &stats);
        return stats.refinedVoxels;
    };
    EXPECT_EQ(refinedVoxels(ramp, 2.0), 18u * 18u * 18u);
    EXPECT_EQ(refinedVoxels(uniform, 2.0), 18u * 18u * 18u - 14u * 14u * 14u);
    EXPECT_EQ(refinedVoxels(ramp, 200.0), 0u);
}

TEST(KernelRefinement, DenseEdgeConvergesToTheReference)
{
    // A box of 2 optical depths a voxel, its edge seen head-on: against the trilinear field's
    // ray march the edge's alpha falls with each refinement, at 8 pixels a voxel (--refine 4
    // applies) and at 3 (--refine 2, whose kernels of 0.75 pixels would be widened to the
    // low-pass filter's pixel if the filter did not scale with the lattice).
    const double h = 0.1;
    auto grid = makeBoxGrid(openvdb::Coord(0), openvdb::Coord(15), 2.0f, h);
    for (const double pixelsPerVoxel : {8.0, 3.0}) {
        const double frame = 40.0 / pixelsPerVoxel; // voxels, centred on the edge x = 15.5
        const CameraSettings cam = orthoDownZ(15.5 * h, 7.5 * h, 3.0, frame * h, 40);
        RenderSettings s = absorberSettings(1.0);
        s.splat.lodPixels = 0.0;
        s.splat.tileKernelSpacing = 1;
        s.splat.slab = 0.25;
        RenderSettings ref = s;
        ref.method = Method::RayMarch;
        ref.step = 0.05;
        const Image reference = renderGrid(grid, cam, ref);
        double previous = 1e30;
        for (const int n : {1, 2, 4}) {
            if (n > pixelsPerVoxel) continue;
            s.splat.refine = n;
            double sum = 0.0;
            const Image img = renderGrid(grid, cam, s);
            for (std::size_t i = 3; i < img.rgba.size(); i += 4) sum += std::pow(double(img.rgba[i]) - reference.rgba[i], 2.0);
            const double e = std::sqrt(sum / double(img.rgba.size() / 4));
            std::printf("dense edge at %.0f pixels a voxel, --refine %d: alpha RMSE against the reference %.4f\n", pixelsPerVoxel, n, e);
            // At 3 pixels a voxel: 0.145, 0.110; 0.150 with the low-pass filter unscaled.
            EXPECT_LT(e, (pixelsPerVoxel > 4.0 ? 0.6 : 0.85) * previous) << "refine " << n << " at " << pixelsPerVoxel << " pixels a voxel";
            previous = e;
        }
    }
}

TEST(KernelRefinement, KeepsToItsBudget)
{
    // 18^3 voxels sampled: n = 4 would make 373,248 kernels, n = 2 46,656. A budget of 1e5
    // lowers n to 2; one of 1e3 leaves the voxel kernels as they are.
    const GridSource ramp = gridSourceFromOpenVDB(makeFogGrid(openvdb::Coord(0), openvdb::Coord(15),
        [](const openvdb::Coord& c) { return float(1.0 + 0.01 * (c.x() + c.y() + c.z())); }, 0.1));
    RenderSettings s;
    s.splat.lodPixels = 0.0;
    CameraSettings cam;
    cam.translate = Vec3d(0.8, 0.8, 2.0);
    const detail::LevelOfDetail scale(ramp.impl(), Camera(cam, Vec3d(0.8)), s);
    for (const double budget : {1e6, 1e5, 1e3}) {
        detail::KernelSet set = detail::extractKernels(ramp.impl(), s);
        const std::size_t voxels = set.kernels.size();
        openvdb::MaskGrid sampled(false);
        const detail::Refinement r = detail::refineKernels(ramp.impl(), 4, 0.0, float(s.cutoff), scale, set, sampled, nullptr, budget);
        EXPECT_EQ(r.n, budget > 2e5 ? 4 : budget > 1e4 ? 2 : 1) << budget;
        EXPECT_EQ(r.lowered, budget < 2e5) << budget;
        EXPECT_LE(double(set.kernels.size()), std::max(budget, double(voxels))) << budget;
        if (r.n == 1) {
            EXPECT_EQ(set.kernels.size(), voxels);
        }
    }
}

TEST(KernelRefinement, WhereItChangesNothingItSaysSo)
{
    // Level sets (surface kernels) and the ray-march reference have no voxel kernels to refine.
    auto sphere = makeBoxGrid(openvdb::Coord(-2), openvdb::Coord(2), -0.1f, 0.1);
    sphere->setGridClass(openvdb::GRID_LEVEL_SET);
    CameraSettings cam;
    cam.width = cam.height = 16;
    cam.translate = Vec3d(0.0, 0.0, 3.0);
    RenderSettings s;
    s.splat.refine = 2;
    RenderStats stats;
    renderGrid(sphere, cam, s, &stats);
    ASSERT_FALSE(stats.warnings.empty());
    EXPECT_NE(stats.warnings.back().find("--refine changes nothing here"), std::string::npos) << stats.warnings.back();
    s.method = Method::RayMarch;
    renderGrid(makeBoxGrid(openvdb::Coord(0), openvdb::Coord(3), 1.0f, 0.1), cam, s, &stats);
    ASSERT_FALSE(stats.warnings.empty());
    EXPECT_NE(stats.warnings.back().find("--method raymarch"), std::string::npos) << stats.warnings.back();
    s.method = Method::Splat;
    renderGrid(makeBoxGrid(openvdb::Coord(0), openvdb::Coord(3), 1.0f, 0.1), cam, s, &stats);
    for (const std::string& w : stats.warnings) EXPECT_EQ(w.find("--refine"), std::string::npos) << w;
}

TEST(KernelRefinement, LowPassFollowsTheLatticeTheKernelIsOn)
{
    // The budget may lower --refine 4 to a lattice of 1/2: those kernels take lowpass / 4, the
    // floor of the lattice they are on, not lowpass / 16 (a 0.1-pixel kernel, floored either way).
    const GridSource voxel = gridSourceFromOpenVDB(makeBoxGrid(openvdb::Coord(0), openvdb::Coord(0), 1.0f, 0.1));
    CameraSettings cam;
    cam.width = cam.height = 64;
    cam.translate = Vec3d(0.0, 0.0, 20.0);
    const Camera camera(cam, Vec3d(0.0));
    detail::KernelSet set;
    set.kernels.push_back({Vec3d(0.0), 1.0f, 0.5f});
    float conic[2] = {0.0f, 0.0f};
    for (const int n : {2, 4}) {
        RenderSettings s;
        s.splat.refine = n;
        const detail::SplatSet splats = detail::projectSplats(voxel.impl(), set, {}, camera, s, PassRequest{});
        ASSERT_EQ(splats.splats.size(), 1u);
        conic[n / 4] = splats.splats[0].qa;
    }
    EXPECT_NEAR(conic[0], 4.0f, 1e-3f); // 1 / (lowpass / 4)
    EXPECT_EQ(conic[1], conic[0]);
}
