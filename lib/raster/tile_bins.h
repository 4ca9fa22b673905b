/// @file tile_bins.h
/// @brief Screen tiles of kTileSize^2 pixels and the splats that overlap each (counting sort
///        in a given order of the splats, so every tile lists its splats deterministically).
#pragma once

#include "support/huge_page_allocator.h"
#include "support/memory_budget.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace vdb_ewa {
namespace detail {

constexpr int kTileSize = 16;
constexpr int kTilePixels = kTileSize * kTileSize;
/// Image-space level of detail's levels of a tile (CompositeOptions::imageLod): level k holds a
/// sample every 2^k pixels, from every pixel (0) to every 8th (3).
constexpr int kImageLevels = 4;

struct TileBins
{
    int tilesX = 0, tilesY = 0;
    std::vector<std::uint64_t> offsets; ///< tilesX * tilesY + 1
    LargeArray<std::uint32_t> indices; ///< splat indices, tile by tile, in the binning order
    std::vector<std::uint32_t> maxSpan; ///< per tile, the largest span(splat) of its splats (0 if none)
};

/// Bins n splats in the order k = 0 .. n - 1: boxOf(k) is the k-th splat's inclusive pixel box
/// (x0, y0, x1, y1 inside the image; empty where x1 < x0 or y1 < y0), indexOf(k) the index
/// listed for it and spanOf(k) its span. Every tile lists its splats in that order (a counting sort, stable, in parallel over
/// fixed chunks of the order: the same lists for any thread count), and keeps the largest span
/// of its splats. @a budget: the pairs are counted against it before they are stored.
template <typename BoxOf, typename IndexOf, typename SpanOf>
TileBins binInOrder(std::size_t n, const BoxOf& boxOf, const IndexOf& indexOf, const SpanOf& spanOf, int width, int height,
    const MemoryBudget* budget = nullptr)
{
    TileBins bins;
    bins.tilesX = (width + kTileSize - 1) / kTileSize;
    bins.tilesY = (height + kTileSize - 1) / kTileSize;
    const std::size_t tiles = std::size_t(bins.tilesX) * bins.tilesY;
    const auto forEachTile = [&](const auto& s, const auto& f) {
        if (s.x1 < s.x0 || s.y1 < s.y0) return; // an empty box
        for (int ty = s.y0 / kTileSize; ty <= s.y1 / kTileSize; ++ty)
            for (int tx = s.x0 / kTileSize; tx <= s.x1 / kTileSize; ++tx) f(std::size_t(ty) * std::size_t(bins.tilesX) + std::size_t(tx));
    };
    // Chunks of the order: each counts its pairs per tile, then writes them from its own cursor
    // (a few for a few splats: each chunk's cursors cover every tile).
    const std::size_t chunks = std::clamp<std::size_t>(n / 4096, 1, 32);
    const std::size_t chunk = (n + chunks - 1) / chunks;
    std::vector<std::uint64_t> cursor(chunks * tiles, 0); // [chunk][tile]: count, then position
    std::vector<std::uint32_t> chunkSpan(chunks * tiles, 0);
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
        std::uint64_t* count = cursor.data() + c * tiles;
        std::uint32_t* most = chunkSpan.data() + c * tiles;
        for (std::size_t k = c * chunk; k < std::min(n, (c + 1) * chunk); ++k) {
            const std::uint32_t sp = spanOf(k);
            forEachTile(boxOf(k), [&](std::size_t t) {
                ++count[t];
                most[t] = std::max(most[t], sp);
            });
        }
    });
    bins.offsets.assign(tiles + 1, 0);
    bins.maxSpan.assign(tiles, 0);
    std::uint64_t next = 0;
    for (std::size_t t = 0; t < tiles; ++t) {
        bins.offsets[t] = next;
        for (std::size_t c = 0; c < chunks; ++c) {
            const std::uint64_t count = cursor[c * tiles + t];
            cursor[c * tiles + t] = next;
            next += count;
            bins.maxSpan[t] = std::max(bins.maxSpan[t], chunkSpan[c * tiles + t]);
        }
    }
    bins.offsets[tiles] = next;
    if (budget) budget->check(double(next), "splat-tile pairs", double(sizeof(std::uint32_t)));
    bins.indices.resize(next);
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
        std::uint64_t* position = cursor.data() + c * tiles;
        for (std::size_t k = c * chunk; k < std::min(n, (c + 1) * chunk); ++k) {
            const std::uint32_t i = indexOf(k);
            forEachTile(boxOf(k), [&](std::size_t t) { bins.indices[position[t]++] = i; });
        }
    });
    return bins;
}

/// Bins splats in their own order.
template <typename Splats>
TileBins binSplats(const Splats& splats, int width, int height, const MemoryBudget* budget = nullptr)
{
    return binInOrder(
        splats.size(), [&](std::size_t k) -> const auto& { return splats[k]; }, [](std::size_t k) { return std::uint32_t(k); },
        [](std::size_t) { return std::uint32_t(1); }, width, height, budget);
}

} // namespace detail
} // namespace vdb_ewa
