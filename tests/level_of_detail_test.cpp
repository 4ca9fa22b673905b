/// @file level_of_detail_test.cpp
/// @brief --lod: the block size chosen per leaf node, mass kept by merging, uniform media
///        unchanged, and the error of merging sub-pixel voxels.
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

} // namespace

TEST(LevelOfDetail, BlockSizeFollowsTheProjectedVoxelSize)
{
    auto grid = makeBoxGrid(openvdb::Coord(0), openvdb::Coord(7), 1.0f, 1.0);
    const GridSource source = gridSourceFromOpenVDB(grid);
    const openvdb::Coord leaf(0);
    // 256 pixels across a 90 degree view: 128 pixels per unit at depth 1.
    for (const double distance : {20.0, 200.0, 2000.0}) {
        const Camera camera(perspectiveDownZ(distance, 256), Vec3d(0.0));
        const detail::LevelOfDetail lod(source.impl(), camera, 4.0);
        const double px = lod.voxelPixels(leaf, 8);
        // The nearest point of the leaf's bounding sphere: centre depth less sqrt(3) * 4 voxels.
        EXPECT_NEAR(px, 128.0 / (distance - 3.5 - std::sqrt(3.0) * 4.0), 1e-9);
        int expected = 1;
        while (2 * expected <= 8 && 2 * expected * px <= 4.0) expected *= 2;
        EXPECT_EQ(lod.blockSize(leaf, 8), expected) << "distance " << distance;
    }
    EXPECT_EQ(detail::LevelOfDetail(source.impl(), Camera(perspectiveDownZ(2000.0, 256), Vec3d(0.0)), 4.0).blockSize(leaf, 8), 8);
    EXPECT_EQ(detail::LevelOfDetail(source.impl(), Camera(perspectiveDownZ(20.0, 256), Vec3d(0.0)), 4.0).blockSize(leaf, 8), 1);
    // Off, or a node reaching the near plane: never merged.
    EXPECT_EQ(detail::LevelOfDetail(source.impl(), Camera(perspectiveDownZ(2000.0, 256), Vec3d(0.0)), 0.0).blockSize(leaf, 8), 1);
    const detail::LevelOfDetail inside(source.impl(), Camera(perspectiveDownZ(5.0, 256), Vec3d(0.0)), 64.0);
    EXPECT_TRUE(std::isinf(inside.voxelPixels(leaf, 8)));
    EXPECT_EQ(inside.blockSize(leaf, 8), 1);
    // Orthographic: frame 64 units over 256 pixels = 4 pixels a voxel, at any depth.
    CameraSettings ortho = orthoDownZ(0.0, 0.0, 1e4, 64.0, 256);
    const detail::LevelOfDetail flat(source.impl(), Camera(ortho, Vec3d(0.0)), 16.0);
    EXPECT_NEAR(flat.voxelPixels(leaf, 8), 4.0, 1e-9);
    EXPECT_EQ(flat.blockSize(leaf, 8), 4);
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
    CameraSettings ortho = orthoDownZ(0.0, 0.0, 100.0, 64.0, 256); // 4 pixels a voxel
    const detail::LevelOfDetail lod(source.impl(), Camera(ortho, Vec3d(0.0)), 16.0);
    const detail::KernelSet set = detail::extractKernels(source.impl(), RenderSettings(), &lod);
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

TEST(LevelOfDetail, OpticalDepthIntegralIsKept)
{
    // An optically thin cloud: the image integral of alpha ~ total optical depth, which
    // merging keeps (mass x projected area per unit volume).
    auto grid = blob(6, 1.0f, 1.0);
    RenderSettings s = absorberSettings(1e-4);
    s.splat.lodPixels = 0.0;
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
