/// @file kernel_extraction.cpp
#include "source/kernel_extraction.h"

#include "source/grid_source_impl.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <bitset>
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

/// Counts @a vc into @a count: [0] below cutoff, [1] NaN, [2] clamped.
void tally(ValueClass vc, std::uint64_t* count)
{
    if (vc == ValueClass::BelowCutoff) ++count[0];
    if (vc == ValueClass::NotANumber) ++count[1];
    if (vc == ValueClass::Clamped) ++count[2];
}

using LeafT = openvdb::FloatTree::LeafNodeType;
static_assert(int(LeafT::DIM) == LevelOfDetail::kLeafDim, "the level of detail's blocks tile a leaf node");

/// A leaf node's values as the level of detail reads them: the sanitised values in offset
/// order (0 where inactive or skipped) and which voxels are active.
struct LeafValues
{
    float density[LeafT::SIZE];
    std::bitset<LeafT::SIZE> active;
};

/// Reads @a leaf into @a out; counts below cutoff, NaN and clamped values into @a count[0..2]
/// when given.
void readLeaf(const LeafT& leaf, float cutoff, LeafValues& out, std::uint64_t* count)
{
    std::fill_n(out.density, LeafT::SIZE, 0.0f);
    out.active.reset();
    for (auto it = leaf.cbeginValueOn(); it; ++it) {
        const ValueClass vc = classify(*it, cutoff, out.density[it.pos()]);
        out.active.set(it.pos());
        if (count) tally(vc, count);
    }
}

/// Calls @a f(offset, level, share) for each active voxel of a merged leaf node and each of the
/// two levels its 2^3 block's continuous level @a levels splits into (LevelOfDetail::split),
/// where the share is positive.
template <typename F>
void forEachShare(const std::bitset<LeafT::SIZE>& active, const float* levels, F&& f)
{
    for (int o = 0; o < int(LeafT::SIZE); ++o) {
        if (!active[o]) continue;
        const LevelOfDetail::Split v = LevelOfDetail::split(levels[LevelOfDetail::blockOf(o, 1)]);
        if (v.upper < 1.0) f(o, v.level, 1.0 - v.upper);
        if (v.upper > 0.0) f(o, v.level + 1, v.upper);
    }
}

/// Slots a merged leaf node needs: one a voxel at level 0 and one a block of a higher level
/// that some active voxel gives a share.
std::size_t sharedSlots(const std::bitset<LeafT::SIZE>& active, const float* levels)
{
    std::size_t voxels = 0;
    std::bitset<LevelOfDetail::kBlocks> blocks[LevelOfDetail::kMaxLevel + 1];
    forEachShare(active, levels, [&](int o, int level, double) {
        if (level == 0) ++voxels;
        else blocks[level].set(std::size_t(LevelOfDetail::blockOf(o, level)));
    });
    for (int l = 1; l <= LevelOfDetail::kMaxLevel; ++l) voxels += blocks[l].count();
    return voxels;
}

/// The kernels of a leaf node the level of detail merges, written from @a out on: each voxel's
/// value goes to its blocks of the two levels of its continuous level @a levels
/// (LevelOfDetail::blockLevels, split), a block's kernel has the mean of what it received
/// over its voxels, at its centre, spacing = block size, so that the mass is kept
/// (docs/equations.md#level-of-detail). Voxels (level 0) first, in offset order, then the
/// blocks of levels 1 to 3. Counts the active voxels with a share above level 0
/// (@a mergedVoxels) and the block kernels (@a mergedKernels).
void shareBetweenLevels(const LeafValues& values, const float* levels, const openvdb::Coord& origin, Kernel* out,
    std::uint64_t& mergedVoxels, std::uint64_t& mergedKernels)
{
    constexpr int kLevels = LevelOfDetail::kMaxLevel + 1;
    double sums[kLevels][LevelOfDetail::kBlocks] = {}; // what each block of levels 1..3 receives
    std::bitset<LeafT::SIZE> merged;
    const Vec3d corner(origin.x(), origin.y(), origin.z());
    forEachShare(values.active, levels, [&](int o, int level, double share) {
        if (level > 0) merged.set(std::size_t(o));
        const double mass = share * double(values.density[o]);
        if (!(mass > 0.0)) return;
        if (level == 0) *out++ = {corner + Vec3d(o >> 6, (o >> 3) & 7, o & 7), float(mass), 1.0f};
        else sums[level][LevelOfDetail::blockOf(o, level)] += mass;
    });
    mergedVoxels += merged.count();
    for (int level = 1; level < kLevels; ++level) {
        const int block = 1 << level, n = LevelOfDetail::kLeafDim >> level;
        const double volume = double(block) * block * block;
        const Vec3d first = corner - 0.5 + 0.5 * double(block);
        for (int bx = 0; bx < n; ++bx)
            for (int by = 0; by < n; ++by)
                for (int bz = 0; bz < n; ++bz) {
                    const double sum = sums[level][(bx * n + by) * n + bz];
                    if (!(sum > 0.0)) continue;
                    *out++ = {first + double(block) * Vec3d(bx, by, bz), float(sum / volume), float(block)};
                    ++mergedKernels;
                }
    }
}

} // namespace

int tileLatticeSpacing(int tileDim, int maxSpacing)
{
    int s = 1;
    while (s * 2 <= std::min(tileDim, maxSpacing)) s *= 2;
    while (tileDim / s > 64) s *= 2;
    return s;
}

std::size_t TileLattice::kernels(int dim) const
{
    const auto cube = [](std::size_t n) { return n * n * n; };
    const std::size_t n = std::size_t(dim / spacing);
    return (upper < 1.0 ? cube(n) : 0) + (upper > 0.0 ? cube(n / 2) : 0);
}

TileLattice tileLattice(const openvdb::CoordBBox& box, int maxSpacing, const LevelOfDetail* lod)
{
    const int dim = box.dim().x();
    TileLattice lattice;
    lattice.spacing = tileLatticeSpacing(dim, maxSpacing);
    if (!lod) return lattice;
    const double seenLarge = std::log2(double(lattice.spacing)), own = std::log2(double(dim));
    const double level = std::clamp(lod->latticeLevel(box.min(), dim), seenLarge, own);
    const int floor = std::min(int(std::floor(level)), int(own));
    lattice.spacing = 1 << floor;
    lattice.upper = floor < int(own) ? level - double(floor) : 0.0;
    return lattice;
}

UnitKernelProbe::UnitKernelProbe(const GridSource::Impl& grid, const RenderSettings& settings, const LevelOfDetail* lod)
    : mGrid(grid), mLod(lod), mCutoff(float(settings.cutoff)), mTileSpacing(settings.splat.tileKernelSpacing),
      mAccessor(grid.grid->tree())
{
}

bool UnitKernelProbe::isUnit(const openvdb::Coord& ijk)
{
    const openvdb::Coord origin = ijk & ~(int(LeafT::DIM) - 1);
    const int offset = int(LeafT::coordToOffset(ijk));
    for (int i = 0; i < mCached; ++i) {
        if (mCache[i].origin == origin) return mCache[i].unit[std::size_t(offset)];
    }
    const LeafT* leaf = mAccessor.probeConstLeaf(ijk);
    if (!leaf) {
        // An active tile's kernels are unit kernels where its lattice spacing is 1.
        if (!mAccessor.isValueOn(ijk)) return false;
        float density = 0.0f;
        const ValueClass vc = classify(mAccessor.getValue(ijk), mCutoff, density);
        if (vc == ValueClass::BelowCutoff || vc == ValueClass::NotANumber || !(density > 0.0f)) return false;
        const int depth = mAccessor.getValueDepth(ijk);
        using Root = openvdb::FloatTree::RootNodeType;
        const int dim = depth == 0 ? int(Root::ChildNodeType::DIM) : depth == 1 ? int(Root::ChildNodeType::ChildNodeType::DIM) : int(LeafT::DIM);
        const openvdb::Coord min = ijk & ~(dim - 1);
        return tileLattice(openvdb::CoordBBox::createCube(min, dim), mTileSpacing, mLod).hasUnitKernels();
    }
    // The leaf's unit kernels as extractKernels makes them: every kept voxel, or where the
    // level of detail merges, the voxels given a positive share at level 0.
    CachedLeaf& entry = mCache[mNext];
    mNext = (mNext + 1) % 8;
    mCached = std::min(mCached + 1, 8);
    entry.origin = origin;
    entry.unit.reset();
    LeafValues values;
    readLeaf(*leaf, mCutoff, values, nullptr);
    const LevelOfDetail::NodeLevels node = mLod ? mLod->nodeLevels(origin, int(LeafT::DIM)) : LevelOfDetail::NodeLevels{-1.0, -1.0};
    if (mLod && node.merges()) {
        float levels[LevelOfDetail::kBlocks];
        mLod->blockLevels(values.density, node, levels);
        forEachShare(values.active, levels, [&](int o, int level, double share) {
            // As shareBetweenLevels writes the kernel and extractKernels keeps it.
            if (level == 0 && float(share * double(values.density[o])) > 0.0f) entry.unit.set(std::size_t(o));
        });
    } else {
        for (int o = 0; o < int(LeafT::SIZE); ++o) entry.unit[std::size_t(o)] = values.active[std::size_t(o)] && values.density[o] > 0.0f;
    }
    return entry.unit[std::size_t(offset)];
}

std::vector<Brick> listBricks(const GridSource::Impl& grid)
{
    const openvdb::FloatTree& tree = grid.grid->tree();
    std::vector<const LeafT*> leaves;
    leaves.reserve(tree.leafCount());
    tree.getNodes(leaves);
    std::vector<Brick> bricks;
    bricks.reserve(leaves.size());
    for (const LeafT* leaf : leaves) bricks.push_back({leaf->getNodeBoundingBox(), leaf, 0.0f});
    auto it = tree.cbeginValueOn();
    it.setMaxDepth(it.getLeafDepth() - 1); // tiles only, no leaf voxels
    for (; it; ++it) {
        if (it.isTileValue()) bricks.push_back({it.getBoundingBox(), nullptr, *it});
    }
    return bricks;
}

KernelSet extractKernels(const GridSource::Impl& grid, const RenderSettings& settings, const LevelOfDetail* lod,
    Progress* progress, const MemoryBudget* budget, const LevelSource* levelsFrom, const std::vector<const Brick*>* only)
{
    const openvdb::FloatTree& tree = grid.grid->tree();
    const float cutoff = float(settings.cutoff);

    KernelSet set;
    std::vector<const LeafT*> leaves;
    // Active tiles: where they are and their values (tree order).
    std::vector<std::pair<openvdb::CoordBBox, float>> activeTiles;
    if (only) {
        for (const Brick* b : *only) {
            if (b->leaf) leaves.push_back(b->leaf);
            else activeTiles.emplace_back(b->box, b->tileValue);
        }
    } else {
        leaves.reserve(tree.leafCount());
        tree.getNodes(leaves);
        auto it = tree.cbeginValueOn();
        it.setMaxDepth(it.getLeafDepth() - 1); // tiles only, no leaf voxels
        for (; it; ++it) {
            if (it.isTileValue()) activeTiles.emplace_back(it.getBoundingBox(), *it);
        }
    }

    // Pass 1: each leaf writes its kernels into its own slot range: one slot per active voxel,
    // or, where the level of detail merges, per voxel or block given a share (sharedSlots;
    // unused slots keep density 0 and are dropped). The merged leaves' levels are kept for
    // pass 2: one float a 2^3 block.
    std::vector<std::size_t> offsets(leaves.size() + 1, 0);
    std::vector<std::uint8_t> merges(leaves.size(), 0);
    std::vector<float> levels;
    std::vector<std::size_t> levelsAt(leaves.size(), 0);
    if (lod) {
        std::vector<LevelOfDetail::NodeLevels> nodes(leaves.size(), LevelOfDetail::NodeLevels{-1.0, -1.0});
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i < range.end(); ++i) {
                nodes[i] = lod->nodeLevels(leaves[i]->origin(), int(LeafT::DIM));
                merges[i] = nodes[i].merges();
            }
        });
        std::size_t merged = 0;
        for (std::size_t i = 0; i < leaves.size(); ++i) levelsAt[i] = merges[i] ? LevelOfDetail::kBlocks * merged++ : 0;
        if (budget) budget->check(double(merged), "level-of-detail leaf nodes", LevelOfDetail::kBlocks * sizeof(float));
        levels.resize(LevelOfDetail::kBlocks * merged);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()), [&](const tbb::blocked_range<std::size_t>& range) {
            LeafValues values, decider;
            for (std::size_t i = range.begin(); i < range.end(); ++i) {
                if (!merges[i]) continue;
                readLeaf(*leaves[i], cutoff, values, nullptr);
                const LeafValues* decides = &values;
                if (levelsFrom) {
                    // Another grid's values choose the levels, so that both merge alike.
                    const LeafT* other = levelsFrom->tree->probeConstLeaf(leaves[i]->origin());
                    if (other) {
                        readLeaf(*other, levelsFrom->cutoff, decider, nullptr);
                    } else {
                        std::fill(std::begin(decider.density), std::end(decider.density), 0.0f);
                    }
                    decides = &decider;
                }
                lod->blockLevels(decides->density, nodes[i], &levels[levelsAt[i]]);
                offsets[i + 1] = sharedSlots(values.active, &levels[levelsAt[i]]);
            }
        });
    }
    for (std::size_t i = 0; i < leaves.size(); ++i) {
        set.activeVoxels += leaves[i]->onVoxelCount();
        offsets[i + 1] = offsets[i] + (merges[i] ? offsets[i + 1] : leaves[i]->onVoxelCount());
    }
    // The slots cost a Kernel each; what the kernels cost further down the pipeline is checked
    // once the level of detail has merged them (Renderer: kBytesPerKernel a kernel).
    if (budget) budget->check(double(offsets.back()), "kernel slots", double(sizeof(Kernel)));
    LargeArray<Kernel> voxels(offsets.back(), Kernel{Vec3d(0.0), 0.0f, 1.0f});
    std::vector<std::uint64_t> counts(leaves.size() * 5, 0); // below cutoff, NaN, clamped, merged voxels, merged kernels
    setUnits(progress, leaves.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()),
        [&](const tbb::blocked_range<std::size_t>& range) {
            LeafValues values;
            for (std::size_t i = range.begin(); i < range.end(); ++i) {
                std::uint64_t* count = &counts[5 * i];
                if (merges[i]) {
                    readLeaf(*leaves[i], cutoff, values, count);
                    shareBetweenLevels(values, &levels[levelsAt[i]], leaves[i]->origin(), &voxels[offsets[i]], count[3], count[4]);
                    continue;
                }
                std::size_t slot = offsets[i];
                for (auto it = leaves[i]->cbeginValueOn(); it; ++it) {
                    float density = 0.0f;
                    tally(classify(*it, cutoff, density), count);
                    const openvdb::Coord c = it.getCoord();
                    voxels[slot++] = {Vec3d(c.x(), c.y(), c.z()), density, 1.0f};
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
        int dim;
        TileLattice lattice;
        float density;
        std::size_t offset;
    };
    std::vector<Tile> tiles;
    std::size_t tileKernels = 0;
    for (const auto& [box, value] : activeTiles) {
        ++set.activeTiles;
        float density = 0.0f;
        const ValueClass vc = classify(value, cutoff, density);
        const int dim = box.dim().x();
        const std::uint64_t voxelsInTile = std::uint64_t(dim) * dim * dim;
        if (vc == ValueClass::BelowCutoff) set.belowCutoff += voxelsInTile;
        if (vc == ValueClass::NotANumber) set.notANumber += voxelsInTile;
        if (vc == ValueClass::Clamped) set.clamped += voxelsInTile;
        if (density <= 0.0f) continue;
        const TileLattice lattice = tileLattice(box, settings.splat.tileKernelSpacing, lod);
        tiles.push_back({box.min(), dim, lattice, density, set.kernels.size() + tileKernels});
        tileKernels += lattice.kernels(dim);
        // Checked tile by tile: a damaged file's millions of tiles stop here, not in the resize.
        if (budget) budget->check(double(set.kernels.size() + tileKernels), "voxel and active-tile kernels", kBytesPerKernel);
    }
    set.kernels.resize(set.kernels.size() + tileKernels);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tiles.size()), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t t = range.begin(); t < range.end(); ++t) {
            const Tile& tile = tiles[t];
            std::size_t slot = tile.offset;
            // Each lattice carries its share of the value: together they keep the tile's mass.
            const auto lattice = [&](int s, double share) {
                const int n = tile.dim / s;
                const Vec3d origin = Vec3d(tile.min.x(), tile.min.y(), tile.min.z()) - 0.5 + 0.5 * s;
                const float density = float(share * double(tile.density));
                for (int i = 0; i < n; ++i)
                    for (int j = 0; j < n; ++j)
                        for (int k = 0; k < n; ++k) set.kernels[slot++] = {origin + double(s) * Vec3d(i, j, k), density, float(s)};
            };
            if (tile.lattice.upper < 1.0) lattice(tile.lattice.spacing, 1.0 - tile.lattice.upper);
            if (tile.lattice.upper > 0.0) lattice(2 * tile.lattice.spacing, tile.lattice.upper);
        }
    });
    return set;
}

} // namespace detail
} // namespace vdb_ewa
