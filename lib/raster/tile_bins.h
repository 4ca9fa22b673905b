/// @file tile_bins.h
/// @brief Screen tiles of kTileSize^2 pixels and the splats that overlap each (counting sort
///        in splat order, so every tile lists its splats deterministically).
#pragma once

#include "support/huge_page_allocator.h"

#include <cstdint>
#include <vector>

namespace vdb_ewa {
namespace detail {

constexpr int kTileSize = 16;
constexpr int kTilePixels = kTileSize * kTileSize;

struct TileBins
{
    int tilesX = 0, tilesY = 0;
    std::vector<std::uint64_t> offsets; ///< tilesX * tilesY + 1
    LargeArray<std::uint32_t> indices; ///< splat indices, tile by tile, in splat order
};

/// @tparam Splats an array of splats, each with an inclusive pixel box x0, y0, x1, y1 inside the image.
template <typename Splats>
TileBins binSplats(const Splats& splats, int width, int height)
{
    TileBins bins;
    bins.tilesX = (width + kTileSize - 1) / kTileSize;
    bins.tilesY = (height + kTileSize - 1) / kTileSize;
    const std::size_t tiles = std::size_t(bins.tilesX) * bins.tilesY;
    bins.offsets.assign(tiles + 1, 0);
    for (const auto& s : splats) {
        for (int ty = s.y0 / kTileSize; ty <= s.y1 / kTileSize; ++ty)
            for (int tx = s.x0 / kTileSize; tx <= s.x1 / kTileSize; ++tx) ++bins.offsets[std::size_t(ty) * bins.tilesX + tx + 1];
    }
    for (std::size_t t = 0; t < tiles; ++t) bins.offsets[t + 1] += bins.offsets[t];
    bins.indices.resize(bins.offsets.back());
    std::vector<std::uint64_t> cursor(bins.offsets.begin(), bins.offsets.end() - 1);
    for (std::uint32_t i = 0; i < splats.size(); ++i) {
        const auto& s = splats[i];
        for (int ty = s.y0 / kTileSize; ty <= s.y1 / kTileSize; ++ty)
            for (int tx = s.x0 / kTileSize; tx <= s.x1 / kTileSize; ++tx) bins.indices[cursor[std::size_t(ty) * bins.tilesX + tx]++] = i;
    }
    return bins;
}

} // namespace detail
} // namespace vdb_ewa
