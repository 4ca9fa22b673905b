/// @file tile_bins_test.cpp
/// @brief Binning splats into screen tiles (raster/tile_bins.h).
#include "raster/raster.h"

#include <gtest/gtest.h>

#include <algorithm>

using namespace vdb_ewa::detail;

namespace {

struct Box
{
    int x0, y0, x1, y1;
};

std::vector<std::uint32_t> listOf(const TileBins& bins, int tx, int ty)
{
    const std::size_t t = std::size_t(ty * bins.tilesX + tx);
    return std::vector<std::uint32_t>(bins.indices.begin() + std::ptrdiff_t(bins.offsets[t]),
        bins.indices.begin() + std::ptrdiff_t(bins.offsets[t + 1]));
}

} // namespace

// Each tile lists the splats whose box overlaps it, in their order; a splat with an empty box
// (x1 < x0: a surface kernel facing the eye outside the frame) is in no tile.
TEST(TileBins, ListsTheOverlappingSplatsAndNoEmptyBox)
{
    const std::vector<Box> boxes = {{0, 0, 20, 5}, {0, 0, -1, -1}, {17, 17, 17, 17}, {3, 3, 3, 3}};
    const TileBins bins = binInOrder(
        boxes.size(), [&](std::size_t k) -> const Box& { return boxes[k]; }, [](std::size_t k) { return std::uint32_t(k); },
        [](std::size_t) { return 1u; }, 40, 40);
    ASSERT_EQ(bins.tilesX, 3);
    ASSERT_EQ(bins.tilesY, 3);
    EXPECT_EQ(listOf(bins, 0, 0), (std::vector<std::uint32_t>{0, 3}));
    EXPECT_EQ(listOf(bins, 1, 0), (std::vector<std::uint32_t>{0}));
    EXPECT_EQ(listOf(bins, 1, 1), (std::vector<std::uint32_t>{2}));
    EXPECT_EQ(bins.indices.size(), 4u);
    EXPECT_EQ(std::count(bins.indices.begin(), bins.indices.end(), 1u), 0);
}
