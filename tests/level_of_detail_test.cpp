/// @file level_of_detail_test.cpp
/// @brief --lod: the continuous level of each leaf node, voxels shared between two levels with
///        their mass kept, merging only smooth blocks above a pixel, images continuous with
///        distance, uniform media unchanged, and the error of merging sub-pixel voxels.
#include "fixtures.h"

#include "source/source.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

/// A looking down -z from z = distance at the origin, 90 degree field of view: a voxel of
/// size h at depth d is h * (width / 2) / d pixels.
CameraSettings perspectiveDownZ(double distance, int res)
{
    CameraSettings c;
    c.width = c.height = res;
    c.translate = Vec3d(0.0, 0.0, distance);
    c.lookAt = Vec3d(0.0);
    c.setFieldOfView(90.0);
    return c;
}

/// A smooth cloud: density rho exp(-|x|^2 / (2 s^2)) over a cube of radius 2 s (voxels).
openvdb::FloatGrid::Ptr blob(int s, float rho, double h)
{
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(h));
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    auto acc = grid->getAccessor();
    for (int i = -2 * s; i <= 2 * s; ++i)
        for (int j = -2 * s; j <= 2 * s; ++j)
            for (int k = -2 * s; k <= 2 * s; ++k) {
                const double r2 = double(i * i + j * j + k * k) / double(s * s);
                acc.setValueOn(openvdb::Coord(i, j, k), float(rho * std::exp(-0.5 * r2)));
            }
    return grid;
}

/// Settings with --lod @a pixels and --lod-error @a error.
RenderSettings lodSettings(double pixels, double error = 1.0)
{
    RenderSettings s;
    // Level of detail where voxels are smaller than a pixel: the frame's own pixels, not the
    // sub-pixels (--supersample) that would make the voxels span 2 of them.
    s.splat.supersample = 1;
    s.splat.lodPixels = pixels;
    s.splat.lodError = error;
    return s;
}

/// Sum of density x spacing^3 over the kernels: the mass, in voxel units.
double massOf(const detail::KernelSet& set)
{
    double m = 0.0;
    for (const auto& k : set.kernels) m += double(k.density) * std::pow(double(k.spacing), 3.0);
    return m;
}

} // namespace

TEST(LevelOfDetail, LevelsFollowTheProjectedVoxelSize)
{
    auto grid = makeBoxGrid(openvdb::Coord(0), openvdb::Coord(7), 1.0f, 1.0);
    const GridSource source = gridSourceFromOpenVDB(grid);
    const openvdb::Coord leaf(0);
    // 256 pixels across a 90 degree view: 128 pixels per unit at depth 1.
    for (const double distance : {20.0, 200.0, 2000.0}) {
        const Camera camera(perspectiveDownZ(distance, 256), Vec3d(0.0));
        const detail::LevelOfDetail lod(source.impl(), camera, lodSettings(4.0));
        const double px = lod.voxelPixels(leaf, 8);
        // The nearest point of the leaf's bounding sphere: centre depth less sqrt(3) * 4 voxels.
        EXPECT_NEAR(px, 128.0 / (distance - 3.5 - std::sqrt(3.0) * 4.0), 1e-9);
        const auto levels = lod.nodeLevels(leaf, 8);
        EXPECT_NEAR(levels.size, std::log2(4.0 / px), 1e-12) << "distance " << distance;
        EXPECT_NEAR(levels.free, std::log2(1.0 / px), 1e-12);
        EXPECT_EQ(levels.merges(), px < 4.0);
    }
    // Off, or a node reaching the near plane: never merged.
    EXPECT_FALSE(detail::LevelOfDetail(source.impl(), Camera(perspectiveDownZ(2000.0, 256), Vec3d(0.0)), lodSettings(0.0))
                     .nodeLevels(leaf, 8)
                     .merges());
    const detail::LevelOfDetail inside(source.impl(), Camera(perspectiveDownZ(5.0, 256), Vec3d(0.0)), lodSettings(64.0));
    EXPECT_TRUE(std::isinf(inside.voxelPixels(leaf, 8)));
    EXPECT_FALSE(inside.nodeLevels(leaf, 8).merges());
    // Orthographic: frame 64 units over 256 pixels = 4 pixels a voxel, at any depth.
    CameraSettings ortho = orthoDownZ(0.0, 0.0, 1e4, 64.0, 256);
    const detail::LevelOfDetail flat(source.impl(), Camera(ortho, Vec3d(0.0)), lodSettings(16.0));
    EXPECT_NEAR(flat.voxelPixels(leaf, 8), 4.0, 1e-9);
    EXPECT_NEAR(flat.nodeLevels(leaf, 8).size, 2.0, 1e-9);
}

TEST(LevelOfDetail, MergedKernelsKeepTheMassAtTheBlockCentres)
{
    // Leaf at the origin: voxels (0..7)^3, merged in blocks of 4 when seen from far away.
    auto grid = openvdb::FloatGrid::create(0.0f);
    auto acc = grid->getAccessor();
    acc.setValueOn(openvdb::Coord(0, 0, 0), 0.8f);
    acc.setValueOn(openvdb::Coord(3, 3, 3), 0.4f);
    acc.setValueOn(openvdb::Coord(5, 1, 2), 0.2f);
    acc.setValueOn(openvdb::Coord(6, 6, 6), 0.001f); // below --cutoff: dropped before merging
    const GridSource source = gridSourceFromOpenVDB(grid);
    CameraSettings ortho = orthoDownZ(0.0, 0.0, 100.0, 64.0, 256); // 4 pixels a voxel: level 2 at --lod 16
    const RenderSettings s = lodSettings(16.0);
    const detail::LevelOfDetail lod(source.impl(), Camera(ortho, Vec3d(0.0)), s);
    const detail::KernelSet set = detail::extractKernels(source.impl(), s, &lod);
    ASSERT_EQ(set.kernels.size(), 2u);
    EXPECT_EQ(set.mergedVoxels, 4u);
    EXPECT_EQ(set.mergedKernels, 2u);
    EXPECT_EQ(set.belowCutoff, 1u);
    // Block (0..3)^3 holds 0.8 + 0.4, block x 4..7, y 0..3, z 0..3 holds 0.2; density x s^3 = mass.
    EXPECT_EQ(set.kernels[0].pIndex, Vec3d(1.5, 1.5, 1.5));
    EXPECT_EQ(set.kernels[0].spacing, 4.0f);
    EXPECT_FLOAT_EQ(set.kernels[0].density * 64.0f, 1.2f);
    EXPECT_EQ(set.kernels[1].pIndex, Vec3d(5.5, 1.5, 1.5));
    EXPECT_FLOAT_EQ(set.kernels[1].density * 64.0f, 0.2f);
}

TEST(LevelOfDetail, BetweenTwoLevelsEachVoxelIsSharedAndTheMassIsKept)
{
    // 2.83 pixels a voxel at --lod 8: level log2(8 / 2.83) = 1.5, each voxel half in its 2^3
    // block, half in its 4^3 block; with quasi-interpolating weights (their halos take the
    // voxels' shares), the mass is still the values' sum.
    auto grid = blob(5, 0.7f, 1.0);
    const GridSource source = gridSourceFromOpenVDB(grid);
    const double px = 4.0 / std::sqrt(2.0);
    const RenderSettings s = lodSettings(8.0);
    const detail::LevelOfDetail lod(source.impl(), Camera(orthoDownZ(0.0, 0.0, 100.0, 256.0 / px, 256), Vec3d(0.0)), s);
    double values = 0.0;
    for (auto it = grid->cbeginValueOn(); it; ++it) values += *it >= float(s.cutoff) ? double(*it) : 0.0;
    detail::KernelSet set = detail::extractKernels(source.impl(), s, &lod);
    EXPECT_EQ(set.mergedVoxels, set.activeVoxels);
    std::size_t level[9] = {};
    for (const auto& k : set.kernels) ++level[int(k.spacing)];
    EXPECT_EQ(level[1] + level[8], 0u);
    EXPECT_GT(level[2], 0u);
    EXPECT_GT(level[4], 0u);
    EXPECT_NEAR(massOf(set), values, 1e-5 * values);
    // Just past a level, 0.02 at --lod 4: one kernel a voxel with share 0.98 (quasi-interpolated
    // below), 2^3 blocks with 0.02. Weights that ignored the share would add 2 % to the mass.
    const detail::LevelOfDetail near(source.impl(), Camera(orthoDownZ(0.0, 0.0, 100.0, 64.0 * std::pow(2.0, 0.02), 256), Vec3d(0.0)),
        lodSettings(4.0));
    EXPECT_NEAR(near.nodeLevels(openvdb::Coord(0), 8).size, 0.02, 1e-9);
    set = detail::extractKernels(source.impl(), s, &near);
    std::fill_n(level, 9, 0u);
    for (const auto& k : set.kernels) ++level[int(k.spacing)];
    EXPECT_GT(level[1], 0u);
    EXPECT_GT(level[2], 0u);
    EXPECT_EQ(level[4] + level[8], 0u);
    EXPECT_NEAR(massOf(set), values, 1e-5 * values);
    const double alpha = detail::quasiInterpolationAlpha(s.splat.kernelSigma);
    ASSERT_GT(detail::quasiInterpolate(source.impl(), alpha, set), 0u);
    // To 1e-4: the active voxels below --cutoff make no kernel but enter their neighbours' weights.
    EXPECT_NEAR(massOf(set), values, 1e-4 * values);
}

TEST(LevelOfDetail, OnlySmoothBlocksMergeAboveAPixel)
{
    // Two leaves 2 pixels a voxel apart at --lod 16 (level 3 by size): one of a smooth ramp, one
    // a checkerboard of 0.2 and 1.0 under sigma_t 1. The ramp's blocks merge; the checkerboard's
    // transmittance across a 2^3 block differs by exp(-0.4) - exp(-2) = 0.53 > 0.05 between its
    // columns (and more across larger blocks), so its voxels stay voxels; seen 8 times smaller
    // its 4^3 blocks span a pixel and merge whatever their values (kFreeMergePixels).
    auto grid = openvdb::FloatGrid::create(0.0f);
    auto acc = grid->getAccessor();
    for (int i = 0; i < 8; ++i)
        for (int j = 0; j < 8; ++j)
            for (int k = 0; k < 8; ++k) {
                acc.setValueOn(openvdb::Coord(i, j, k), 0.5f + 0.001f * float(i));
                acc.setValueOn(openvdb::Coord(8 + i, j, k), (i + j + k) % 2 ? 1.0f : 0.2f);
            }
    const GridSource source = gridSourceFromOpenVDB(grid);
    RenderSettings s = lodSettings(16.0, 0.05);
    s.medium.absorb = Vec3d(1.0);
    s.medium.scatter = Vec3d(0.0);
    const detail::LevelOfDetail lod(source.impl(), Camera(orthoDownZ(0.0, 0.0, 100.0, 128.0, 256), Vec3d(0.0)), s);
    EXPECT_TRUE(lod.smoothBlock(0.5f, 0.507f, 8));
    EXPECT_FALSE(lod.smoothBlock(0.2f, 1.0f, 2));
    // Dense: across all 8 voxels the columns differ by exp(-4) - exp(-8) = 0.018 only, but one
    // voxel deep, where a ray shows the block's surface, by exp(-0.69) - exp(-1.39) = 0.25.
    EXPECT_FALSE(lod.smoothBlock(0.5f, 1.0f, 8));
    EXPECT_TRUE(lod.smoothBlock(0.0f, 0.006f, 8)); // faint: 1 - exp(-0.048)
    const detail::KernelSet set = detail::extractKernels(source.impl(), s, &lod);
    std::size_t ramp[9] = {}, checker[9] = {};
    for (const auto& k : set.kernels) ++(k.pIndex.x < 7.75 ? ramp : checker)[int(k.spacing)];
    EXPECT_EQ(ramp[8], 1u);
    EXPECT_EQ(ramp[1] + ramp[2] + ramp[4], 0u);
    EXPECT_EQ(checker[1], 512u);
    EXPECT_EQ(checker[2] + checker[4] + checker[8], 0u);
    const detail::LevelOfDetail small(source.impl(), Camera(orthoDownZ(0.0, 0.0, 100.0, 1024.0, 256), Vec3d(0.0)), s);
    std::size_t far[9] = {};
    for (const auto& k : detail::extractKernels(source.impl(), s, &small).kernels) ++far[int(k.spacing)];
    EXPECT_EQ(far[8], 1u); // the ramp
    EXPECT_EQ(far[4], 8u); // the checkerboard
    EXPECT_EQ(far[1] + far[2], 0u);
    // By size alone (--lod-error 1) both merge into one kernel.
    const RenderSettings sizeOnly = lodSettings(16.0, 1.0);
    const detail::LevelOfDetail bySize(source.impl(), Camera(orthoDownZ(0.0, 0.0, 100.0, 128.0, 256), Vec3d(0.0)), sizeOnly);
    EXPECT_EQ(detail::extractKernels(source.impl(), sizeOnly, &bySize).kernels.size(), 2u);
}

TEST(LevelOfDetail, ImagesAreContinuousWithDistance)
{
    // A leaf node seen where its voxels cross 2 pixels at --lod 8 (from 2^3 to 4^3 blocks):
    // moving the camera back by 1e-3 of its distance changes the image by at most 1.5x what the
    // same move changes without level of detail. With one level per leaf node (before the
    // shares), the image jumped by the difference of the two levels there: 0.30 against
    // 6.4e-3 without level of detail.
    auto grid = blob(3, 2.0f, 1.0);
    RenderSettings s = lodSettings(8.0, 1.0);
    // The blob spans leaves (-8..-1) and (0..7) on each axis; the nearer leaves' voxels span 2
    // pixels where their bounding spheres' nearest points are 64 units deep (128 pixels a unit
    // at depth 1): camera at 64 + 3.5 (their centres) + 4 sqrt(3) (their radius).
    const double crossing = 64.0 + 3.5 + 4.0 * std::sqrt(3.0);
    const CameraSettings before = perspectiveDownZ(crossing * (1.0 - 5e-4), 256), after = perspectiveDownZ(crossing * (1.0 + 5e-4), 256);
    const Image a = renderGrid(grid, before, s), b = renderGrid(grid, after, s);
    s.splat.lodPixels = 0.0;
    const Image c = renderGrid(grid, before, s), d = renderGrid(grid, after, s);
    const double withLod = maxAbsDiff(a, b), without = maxAbsDiff(c, d), levels = maxAbsDiff(a, c);
    std::printf("1e-3 of the distance across a level: %.2e with --lod 8, %.2e without; --lod 8 changes the image by %.2e\n",
        withLod, without, levels);
    EXPECT_GT(levels, 0.01); // the level of detail does change the image
    EXPECT_LT(withLod, 1.5 * without);
}

TEST(LevelOfDetail, OpticalDepthIntegralIsKept)
{
    // An optically thin cloud: the image integral of alpha ~ total optical depth, which
    // merging keeps (mass x projected area per unit volume).
    auto grid = blob(6, 1.0f, 1.0);
    RenderSettings s = absorberSettings(1e-4);
    s.splat.lodPixels = 0.0;
    s.splat.supersample = 1; // merging at the frame's pixels (sub-pixels would make voxels span 2)
    const CameraSettings cam = perspectiveDownZ(400.0, 256); // a voxel is 0.32 pixels
    RenderStats plain, merged;
    const Image a = renderGrid(grid, cam, s, &plain);
    s.splat.lodPixels = 2.0;
    const Image b = renderGrid(grid, cam, s, &merged);
    EXPECT_EQ(plain.voxelsMerged, 0u);
    EXPECT_EQ(merged.voxelsMerged, merged.activeVoxels);
    EXPECT_LT(merged.kernels * 20, plain.kernels);
    EXPECT_NEAR(alphaSum(b), alphaSum(a), 0.005 * alphaSum(a));
}

TEST(LevelOfDetail, UniformMediumIsUnchanged)
{
    // Merged kernels on a coarser lattice keep the partition of unity: a uniform slab still
    // transmits exp(-tau).
    const double sigma = 0.2, rho = 0.5;
    auto grid = makeBoxGrid(openvdb::Coord(-32, -32, 0), openvdb::Coord(31, 31, 15), float(rho), 1.0);
    RenderSettings s = absorberSettings(sigma);
    s.splat.lodPixels = 4.0;
    s.splat.supersample = 1; // merging at the frame's pixels (sub-pixels would make voxels span 2)
    RenderStats stats;
    const Image img = renderGrid(grid, orthoDownZ(-0.5, -0.5, 100.0, 16.0, 8), s, &stats); // 0.5 pixels a voxel
    EXPECT_EQ(stats.voxelsMerged, stats.activeVoxels);
    const double expected = 1.0 - std::exp(-sigma * rho * 16.0);
    for (std::size_t i = 3; i < img.rgba.size(); i += 4) ASSERT_NEAR(img.rgba[i], expected, 0.005 * expected);
}

TEST(LevelOfDetail, SubPixelVoxelsMergeWithASmallError)
{
    // A cloud seen so small that voxels are a fraction of a pixel: the low-pass filter
    // dominates every footprint, so merging them barely changes the image.
    auto grid = blob(12, 0.5f, 1.0);
    RenderSettings s;
    s.splat.lodPixels = 0.0;
    s.splat.supersample = 1; // merging at the frame's pixels (sub-pixels would make voxels span 2)
    const CameraSettings cam = perspectiveDownZ(600.0, 256); // a voxel ~ 0.22 pixels
    RenderStats plain, merged;
    const Image a = renderGrid(grid, cam, s, &plain);
    s.splat.lodPixels = 1.0; // blocks of up to 4 voxels
    const Image b = renderGrid(grid, cam, s, &merged);
    EXPECT_GT(merged.voxelsMerged, 0u);
    EXPECT_LT(merged.kernels * 8, plain.kernels);
    double peak = 0.0;
    for (std::size_t i = 3; i < a.rgba.size(); i += 4) peak = std::max(peak, double(a.rgba[i]));
    ASSERT_GT(peak, 0.3);
    const double e = rmse(a, b);
    std::printf("--lod 1 on a cloud of 0.22-pixel voxels: %llu -> %llu kernels, RMSE %.2e (alpha peak %.2f)\n",
        (unsigned long long)plain.kernels, (unsigned long long)merged.kernels, e, peak);
    EXPECT_LT(e, 2e-3);
}
