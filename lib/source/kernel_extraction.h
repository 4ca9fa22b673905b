/// @file kernel_extraction.h
/// @brief Active voxels and active tiles -> Gaussian reconstruction kernels (Eq. 1, 8, 19).
#pragma once

#include <vdb_ewa/grid_source.h>
#include <vdb_ewa/render_settings.h>

#include "source/grid_source_impl.h"
#include "source/level_of_detail.h"
#include "support/huge_page_allocator.h"
#include "support/memory_budget.h"
#include "support/progress.h"

#include <array>
#include <bitset>
#include <cstdint>
#include <limits>
#include <algorithm>
#include <cmath>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// One reconstruction kernel r_k = G_V(u - u_k): a voxel (spacing 1), a block of s^3 voxels
/// merged for level of detail, or one kernel of the lattice that models an active tile
/// (spacing s > 1: sigma and weight scale with s).
struct Kernel
{
    Vec3d pIndex;   ///< centre, index space
    float density;  ///< sanitised voxel value (>= cutoff, <= kMaxDensity); after quasiInterpolate, the kernel's weight (halo kernels < 0)
    float spacing;  ///< lattice spacing in voxels: sigma = kernelSigmaVoxels(), weight x spacing^3
};

/// Standard deviation of kernels on a lattice coarser than the voxels (active tiles, level of
/// detail): large enough that their sum over a uniform region is flat (partition of unity to
/// 1.5 %, docs/numerics.md#kernel-standard-deviation), since such regions are uniform or
/// already smoothed; voxel kernels keep --kernel-sigma, sharper for thin dense media.
inline constexpr double kCoarseKernelSigma = 0.6;

/// The standard deviation of kernel @a k in voxel lengths (Eq. 19, V = sigma^2 I in index space).
inline double kernelSigmaVoxels(const Kernel& k, double kernelSigma)
{
    const double s = double(k.spacing);
    return (s > 1.0 ? std::max(kernelSigma, kCoarseKernelSigma) : kernelSigma) * s;
}

/// A kernel of the voxel lattice itself (a voxel, or an active tile's kernel at spacing 1).
inline bool isUnitKernel(const Kernel& k) { return k.spacing == 1.0f; }

/// The voxel a unit kernel stands for.
inline openvdb::Coord voxelOf(const Kernel& k)
{
    return openvdb::Coord(int(std::lround(k.pIndex.x)), int(std::lround(k.pIndex.y)), int(std::lround(k.pIndex.z)));
}

/// Motion blur (kernel_motion.h): where a kernel is at the shutter's mid-time, from its still
/// centre, and its path over the shutter (or its share of it), world units.
struct KernelMotion
{
    float shift[3];
    float path[3];
    /// The shutter layers (MotionBlur::layers) its piece of the shutter covers: the first and
    /// how many; 0 of them: all (the path was not split, or layers are off).
    std::uint16_t layerFirst = 0, layerCount = 0;
};

struct KernelSet
{
    LargeArray<Kernel> kernels; ///< in tree order (deterministic)
    /// Motion blur: one per kernel, or empty (no velocity grid, or nothing moves).
    LargeArray<KernelMotion> motion;
    std::uint64_t activeVoxels = 0;
    std::uint64_t activeTiles = 0;
    std::uint64_t belowCutoff = 0; ///< values < cutoff (including negative and -Inf): skipped
    std::uint64_t notANumber = 0;  ///< NaN values: skipped
    std::uint64_t clamped = 0;     ///< values > kMaxDensity (including +Inf): clamped
    std::uint64_t mergedVoxels = 0; ///< active voxels merged into level-of-detail kernels
    std::uint64_t mergedKernels = 0; ///< level-of-detail kernels they became
    /// Kernels from emitterBegin on are emitters (emission grids, EmitterKernels): no optical
    /// depth, radiance emitted[i - emitterBegin] per unit weight and voxel length.
    std::size_t emitterBegin = std::numeric_limits<std::size_t>::max();
    std::vector<std::array<float, 3>> emitted;
};

/// Lattice spacing (voxels) used for an active tile of @a tileDim voxels a side seen large:
/// the largest power of two <= min(tileDim, maxSpacing), but coarse enough that a tile yields
/// at most 64^3 kernels. See docs/equations.md#active-tiles.
int tileLatticeSpacing(int tileDim, int maxSpacing);

/// The lattices an active tile becomes (docs/equations.md#active-tiles-seen-small): kernels
/// @c spacing voxels apart carrying 1 - @c upper of its value and, where @c upper > 0, kernels
/// twice as far apart carrying the rest. Seen small, the spacing follows the pixels up to the
/// tile's own size, continuously in the camera (no popping), the tile's optical depth kept.
struct TileLattice
{
    int spacing = 1;
    double upper = 0.0;
    /// The widest kernel spacing it makes.
    int widest() const { return upper > 0.0 ? 2 * spacing : spacing; }
    /// True if it makes kernels of the voxel lattice (isUnitKernel).
    bool hasUnitKernels() const { return spacing == 1 && upper < 1.0; }
    /// How many kernels it makes over a tile of @a dim voxels a side.
    std::size_t kernels(int dim) const;
};

/// The lattices of the active tile @a box (a cube of a power-of-two side): with @a lod, the
/// continuous level clamp(LevelOfDetail::latticeLevel, log2(tileLatticeSpacing), log2(side))
/// split between its floor and the next; without, tileLatticeSpacing alone.
TileLattice tileLattice(const openvdb::CoordBBox& box, int maxSpacing, const LevelOfDetail* lod);

/// The streamed frame's unit of work (docs/architecture.md#the-streamed-frame): a leaf node of
/// the grid, or one of its active tiles.
struct Brick
{
    openvdb::CoordBBox box; ///< the index-space voxels it covers
    const openvdb::FloatTree::LeafNodeType* leaf = nullptr; ///< null: an active tile
    float tileValue = 0.0f; ///< an active tile's value
};

/// Build the kernels of every active voxel and tile, one TBB task per leaf node. With @a lod,
/// a leaf node whose voxels project small enough becomes blocks of merged kernels (the
/// block's mean density at the block's centre, spacing = block size: mass is kept).
/// @a progress: one unit per leaf node; throws Cancelled. @a budget: the voxels' and the active
/// tiles' kernels are counted against it before they are allocated (BudgetError).
/// @a levelsFrom: where given, the level of detail's blocks take the levels this grid's values
/// give (values below its cutoff read as 0): an emission grid merges as the density does, so
/// that their kernels keep the same shapes (docs/equations.md#emission-grids).
/// @a only: the kernels of these bricks alone (in this order), as the whole grid's would be
/// (the streamed frame's windows); null: every brick's, in tree order.
struct LevelSource
{
    const openvdb::FloatTree* tree;
    float cutoff;
};
KernelSet extractKernels(const GridSource::Impl& grid, const RenderSettings& settings,
    const LevelOfDetail* lod = nullptr, Progress* progress = nullptr, const MemoryBudget* budget = nullptr,
    const LevelSource* levelsFrom = nullptr, const std::vector<const Brick*>* only = nullptr);

/// Every leaf node of @a grid in tree order, then every active tile in tree order.
std::vector<Brick> listBricks(const GridSource::Impl& grid);

/// Which voxels hold a unit kernel (isUnitKernel: a voxel at level 0 of the level of detail,
/// or an active tile's kernel of spacing 1) as extractKernels makes them for the whole grid:
/// quasiInterpolate's halo rule, for a window of bricks whose neighbours are not extracted.
/// One probe per thread: it caches the leaf nodes it read.
class UnitKernelProbe
{
public:
    UnitKernelProbe(const GridSource::Impl& grid, const RenderSettings& settings, const LevelOfDetail* lod);
    bool isUnit(const openvdb::Coord& ijk);

private:
    struct CachedLeaf
    {
        openvdb::Coord origin;
        std::bitset<512> unit;
    };
    const GridSource::Impl& mGrid;
    const LevelOfDetail* mLod;
    float mCutoff;
    int mTileSpacing;
    openvdb::FloatGrid::ConstAccessor mAccessor;
    CachedLeaf mCache[8];
    int mCached = 0, mNext = 0;
};

} // namespace detail
} // namespace vdb_ewa
