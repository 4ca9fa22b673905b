/// @file kernel_extraction.cpp
#include "source/kernel_extraction.h"

#include "source/grid_source_impl.h"

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

KernelSet extractKernels(const GridSource::Impl& grid, const RenderSettings& settings, const LevelOfDetail* lod,
    Progress* progress, const MemoryBudget* budget)
{
    using LeafT = openvdb::FloatTree::LeafNodeType;
    const openvdb::FloatTree& tree = grid.grid->tree();
    const float cutoff = float(settings.cutoff);

    KernelSet set;
    std::vector<const LeafT*> leaves;
    leaves.reserve(tree.leafCount());
    tree.getNodes(leaves);

    // Pass 1: each leaf writes its kernels into its own slot range: one slot per active voxel,
    // or per block where the level of detail merges blocks of voxels (at most as many as the
    // leaf's active voxels; unused slots keep density 0 and are dropped).
    std::vector<std::size_t> offsets(leaves.size() + 1, 0);
    std::vector<int> blockSizes(leaves.size(), 1);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            const int block = lod ? lod->blockSize(leaves[i]->origin(), int(LeafT::DIM)) : 1;
            const std::size_t blocks = std::size_t(LeafT::DIM / block) * std::size_t(LeafT::DIM / block) * std::size_t(LeafT::DIM / block);
            blockSizes[i] = block;
            offsets[i + 1] = std::min<std::size_t>(leaves[i]->onVoxelCount(), blocks);
        }
    });
    for (std::size_t i = 0; i < leaves.size(); ++i) {
        set.activeVoxels += leaves[i]->onVoxelCount();
        offsets[i + 1] += offsets[i];
    }
    // The slots cost a Kernel each; what the kernels cost further down the pipeline is checked
    // once the level of detail has merged them (Renderer: kBytesPerKernel a kernel).
    if (budget) budget->check(double(offsets.back()), "kernel slots", double(sizeof(Kernel)));
    LargeArray<Kernel> voxels(offsets.back(), Kernel{Vec3d(0.0), 0.0f, 1.0f});
    std::vector<std::uint64_t> counts(leaves.size() * 5, 0); // below cutoff, NaN, clamped, merged voxels, merged kernels
    setUnits(progress, leaves.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()),
        [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i < range.end(); ++i) {
                std::uint64_t* count = &counts[5 * i];
                const openvdb::Coord origin = leaves[i]->origin();
                const int block = blockSizes[i];
                const int blocks = int(LeafT::DIM) / block;
                float sums[LeafT::SIZE] = {}; // per block, used when block > 1
                std::size_t slot = offsets[i];
                for (auto it = leaves[i]->cbeginValueOn(); it; ++it) {
                    float density = 0.0f;
                    const ValueClass vc = classify(*it, cutoff, density);
                    if (vc == ValueClass::BelowCutoff) ++count[0];
                    if (vc == ValueClass::NotANumber) ++count[1];
                    if (vc == ValueClass::Clamped) ++count[2];
                    const openvdb::Coord c = it.getCoord();
                    if (block == 1) {
                        voxels[slot++] = {Vec3d(c.x(), c.y(), c.z()), density, 1.0f};
                        continue;
                    }
                    const int bx = (c.x() - origin.x()) / block, by = (c.y() - origin.y()) / block,
                              bz = (c.z() - origin.z()) / block;
                    sums[(bx * blocks + by) * blocks + bz] += density;
                    ++count[3];
                }
                if (block == 1) continue;
                // Merged kernel: the block's mean density at its centre (docs/equations.md#level-of-detail).
                const double volume = double(block) * block * block;
                const Vec3d first = Vec3d(origin.x(), origin.y(), origin.z()) - 0.5 + 0.5 * double(block);
                for (int bx = 0; bx < blocks; ++bx)
                    for (int by = 0; by < blocks; ++by)
                        for (int bz = 0; bz < blocks; ++bz) {
                            const float sum = sums[(bx * blocks + by) * blocks + bz];
                            if (!(sum > 0.0f)) continue;
                            voxels[slot++] = {first + double(block) * Vec3d(bx, by, bz), float(double(sum) / volume), float(block)};
                            ++count[4];
                        }
            }
            advance(progress, range.size());
        });
    for (std::size_t i = 0; i < leaves.size(); ++i) {
        set.belowCutoff += counts[5 * i];
        set.notANumber += counts[5 * i + 1];
        set.clamped += counts[5 * i + 2];
        set.mergedVoxels += counts[5 * i + 3];
        set.mergedKernels += counts[5 * i + 4];
    }
    // Compacted in place (stable: tree order), without a second array of kernels to touch.
    voxels.erase(std::remove_if(voxels.begin(), voxels.end(), [](const Kernel& k) { return !(k.density > 0.0f); }),
        voxels.end());
    // Where the level of detail merged most voxels, the slots' memory goes back.
    if (voxels.size() < voxels.capacity() / 2) voxels.shrink_to_fit();
    set.kernels = std::move(voxels);

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
        const int s = tileLatticeSpacing(dim, settings.splat.tileKernelSpacing);
        tiles.push_back({box.min(), dim, s, density, set.kernels.size() + tileKernels});
        const std::size_t n = std::size_t(dim / s);
        tileKernels += n * n * n;
        // Checked tile by tile: a damaged file's millions of tiles stop here, not in the resize.
        if (budget) budget->check(double(set.kernels.size() + tileKernels), "voxel and active-tile kernels", kBytesPerKernel);
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
