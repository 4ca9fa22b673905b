/// @file kernel_extraction.cpp
#include "kernel_extraction.h"

#include "grid_source_impl.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace vdb_ewa {
namespace detail {
namespace {

enum class ValueClass { Keep, BelowCutoff, NotANumber, Clamped };

ValueClass classify(float value, float cutoff, float& density)
{
    if (std::isnan(value)) return ValueClass::NotANumber;
    if (!(value >= cutoff)) return ValueClass::BelowCutoff;
    if (value > kMaxDensity) {
        density = kMaxDensity;
        return ValueClass::Clamped;
    }
    density = value;
    return ValueClass::Keep;
}

} // namespace

int tileLatticeSpacing(int tileDim, int maxSpacing)
{
    int s = 1;
    while (s * 2 <= std::min(tileDim, maxSpacing)) s *= 2;
    while (tileDim / s > 64) s *= 2;
    return s;
}

KernelSet extractKernels(const GridSource::Impl& grid, const RenderSettings& settings)
{
    using LeafT = openvdb::FloatTree::LeafNodeType;
    const openvdb::FloatTree& tree = grid.grid->tree();
    const float cutoff = float(settings.cutoff);

    KernelSet set;
    std::vector<const LeafT*> leaves;
    leaves.reserve(tree.leafCount());
    tree.getNodes(leaves);

    // Pass 1: each leaf writes its active voxels into its own slot range.
    std::vector<std::size_t> offsets(leaves.size() + 1, 0);
    for (std::size_t i = 0; i < leaves.size(); ++i) offsets[i + 1] = offsets[i] + leaves[i]->onVoxelCount();
    set.activeVoxels = offsets.back();
    std::vector<Kernel> voxels(offsets.back());
    std::vector<std::uint64_t> counts(leaves.size() * 3, 0); // below cutoff, NaN, clamped
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()),
        [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i < range.end(); ++i) {
                std::size_t slot = offsets[i];
                for (auto it = leaves[i]->cbeginValueOn(); it; ++it, ++slot) {
                    Kernel& k = voxels[slot];
                    const openvdb::Coord c = it.getCoord();
                    k.pIndex = Vec3d(c.x(), c.y(), c.z());
                    k.spacing = 1.0f;
                    k.density = 0.0f;
                    const ValueClass vc = classify(*it, cutoff, k.density);
                    if (vc == ValueClass::BelowCutoff) ++counts[3 * i];
                    if (vc == ValueClass::NotANumber) ++counts[3 * i + 1];
                    if (vc == ValueClass::Clamped) ++counts[3 * i + 2];
                }
            }
        });
    for (std::size_t i = 0; i < leaves.size(); ++i) {
        set.belowCutoff += counts[3 * i];
        set.notANumber += counts[3 * i + 1];
        set.clamped += counts[3 * i + 2];
    }
    set.kernels.reserve(voxels.size());
    std::copy_if(voxels.begin(), voxels.end(), std::back_inserter(set.kernels),
        [](const Kernel& k) { return k.density > 0.0f; });

    // Active tiles: a lattice of larger kernels (rule in docs/equations.md#active-tiles).
    // Collect them in tree order, then expand them in parallel into their own slot ranges.
    struct Tile
    {
        openvdb::Coord min;
        int dim, spacing;
        float density;
        std::size_t offset;
    };
    std::vector<Tile> tiles;
    std::size_t tileKernels = 0;
    auto it = tree.cbeginValueOn();
    it.setMaxDepth(it.getLeafDepth() - 1); // tiles only, no leaf voxels
    for (; it; ++it) {
        if (!it.isTileValue()) continue;
        ++set.activeTiles;
        float density = 0.0f;
        const ValueClass vc = classify(*it, cutoff, density);
        const openvdb::CoordBBox box = it.getBoundingBox();
        const int dim = box.dim().x();
        const std::uint64_t voxelsInTile = std::uint64_t(dim) * dim * dim;
        if (vc == ValueClass::BelowCutoff) set.belowCutoff += voxelsInTile;
        if (vc == ValueClass::NotANumber) set.notANumber += voxelsInTile;
        if (vc == ValueClass::Clamped) set.clamped += voxelsInTile;
        if (density <= 0.0f) continue;
        const int s = tileLatticeSpacing(dim, settings.tileKernelSpacing);
        tiles.push_back({box.min(), dim, s, density, set.kernels.size() + tileKernels});
        const std::size_t n = std::size_t(dim / s);
        tileKernels += n * n * n;
    }
    set.kernels.resize(set.kernels.size() + tileKernels);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tiles.size()), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t t = range.begin(); t < range.end(); ++t) {
            const Tile& tile = tiles[t];
            const int s = tile.spacing, n = tile.dim / s;
            const Vec3d origin = Vec3d(tile.min.x(), tile.min.y(), tile.min.z()) - 0.5 + 0.5 * s;
            std::size_t slot = tile.offset;
            for (int i = 0; i < n; ++i)
                for (int j = 0; j < n; ++j)
                    for (int k = 0; k < n; ++k) {
                        set.kernels[slot++] = {origin + double(s) * Vec3d(i, j, k), tile.density, float(s)};
                    }
        }
    });
    return set;
}

} // namespace detail
} // namespace vdb_ewa
