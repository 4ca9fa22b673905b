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

// Any number of splats, in one chunk of the order, a few, or the most (32): every tile lists
// exactly the splats whose box overlaps it, in their order, and the largest span among them
// (against a brute-force reference).
TEST(TileBins, ListsEverySplatInOrderWhateverTheChunks)
{
    for (const std::size_t n : {std::size_t(1), std::size_t(4095), std::size_t(20001), std::size_t(200003)}) {
        std::vector<Box> boxes(n);
        std::vector<std::uint32_t> spans(n);
        std::uint32_t seed = 12345;
        const auto next = [&](int range) {
            seed = seed * 1664525u + 1013904223u;
            return int((seed >> 8) % std::uint32_t(range));
        };
        for (std::size_t k = 0; k < n; ++k) {
            const int x = next(100) - 10, y = next(80) - 10; // some boxes start outside the image
            boxes[k] = next(50) == 0 ? Box{0, 0, -1, -1} : Box{std::max(x, 0), std::max(y, 0), std::min(x + next(40), 89), std::min(y + next(40), 69)};
            spans[k] = std::uint32_t(next(7) + 1);
        }
        const TileBins bins = binInOrder(
            n, [&](std::size_t k) -> const Box& { return boxes[k]; }, [](std::size_t k) { return std::uint32_t(k); },
            [&](std::size_t k) { return spans[k]; }, 90, 70);
        std::size_t pairs = 0;
        for (int ty = 0; ty < bins.tilesY; ++ty)
            for (int tx = 0; tx < bins.tilesX; ++tx) {
                std::vector<std::uint32_t> expected;
                std::uint32_t widest = 0;
                for (std::size_t k = 0; k < n; ++k) {
                    const Box& b = boxes[k];
                    if (b.x1 < b.x0 || b.y1 < b.y0) continue;
                    if (b.x0 / kTileSize <= tx && tx <= b.x1 / kTileSize && b.y0 / kTileSize <= ty && ty <= b.y1 / kTileSize) {
                        expected.push_back(std::uint32_t(k));
                        widest = std::max(widest, spans[k]);
                    }
                }
                pairs += expected.size();
                ASSERT_EQ(listOf(bins, tx, ty), expected) << n << " splats, tile " << tx << "," << ty;
                EXPECT_EQ(bins.maxSpan[std::size_t(ty * bins.tilesX + tx)], widest);
            }
        EXPECT_EQ(bins.indices.size(), pairs);
    }
}
