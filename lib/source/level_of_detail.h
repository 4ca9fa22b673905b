/// @file level_of_detail.h
/// @brief Level of detail: where voxels project smaller than --lod pixels, their mass is shared
///        between two levels of blocks of 2^L voxels a side merged into one kernel, with shares
///        continuous in the camera, and a block merges only where its values are smooth
///        enough (docs/equations.md#level-of-detail).
#pragma once

#include <vdb_ewa/camera.h>
#include <vdb_ewa/grid_source.h>
#include <vdb_ewa/render_settings.h>

#include "support/openvdb.h"

#include <algorithm>
#include <limits>

namespace vdb_ewa {
namespace detail {

class LevelOfDetail
{
public:
    /// Blocks of up to 2^kMaxLevel = 8 voxels a side: a leaf node.
    static constexpr int kMaxLevel = 3;
    static constexpr int kLeafDim = 1 << kMaxLevel;
    static constexpr int kLeafSize = kLeafDim * kLeafDim * kLeafDim;
    /// 2^3 blocks in a leaf node: all voxels of one share its level.
    static constexpr int kBlocks = kLeafSize / 8;

    /// Index of the block of level @a level (2^level voxels a side) holding leaf offset @a o
    /// (OpenVDB's leaf order: x << 6 | y << 3 | z), blocks in the same x-major order.
    static int blockOf(int o, int level)
    {
        const int n = kLeafDim >> level;
        return ((((o >> 6) & 7) >> level) * n + (((o >> 3) & 7) >> level)) * n + ((o & 7) >> level);
    }

    /// Where a block's spacing projects to at most this many pixels, the block merges whatever
    /// its values: the screen-space low-pass filter (one pixel^2, Eq. 33) dominates its footprint.
    static constexpr double kFreeMergePixels = 1.0;

    /// --lod (settings.splat.lodPixels, 0 = no merging) and --lod-error (settings.splat.lodError)
    /// with the medium's extinction from @a settings. @a widestLattice: the widest spacing
    /// (voxels) latticeLevel may reach, the frame's slabs' (widestLatticeSpacing,
    /// splat_projection.h); +inf: no limit.
    LevelOfDetail(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings,
        double widestLattice = std::numeric_limits<double>::infinity());

    /// How many pixels a lattice over a uniform region (an active tile) may span between its
    /// kernels: --lod, or at --lod 0 --supersample-span, what sub-pixels make a voxel span
    /// (docs/equations.md#active-tiles-seen-small).
    static double latticePixels(const SplatOptions& splat) { return splat.lodPixels > 0.0 ? splat.lodPixels : splat.supersampleSpan; }

    /// The continuous level (log2 of a spacing in voxels) of a lattice over the uniform node
    /// whose voxels span [min, min + dim - 1]: log2(latticePixels / voxelPixels), the spacing
    /// that projects to latticePixels at the node's nearest point, at most
    /// log2(widestLattice) - 1 (so that the two spacings a level splits between stay within
    /// it); -inf where the node reaches the near plane. Continuous in the camera.
    double latticeLevel(const openvdb::Coord& min, int dim) const;

    /// The continuous levels of the node whose voxels span [min, min + dim - 1]: @c size =
    /// log2(lodPixels / voxelPixels) (the level a block reaches at which its spacing projects
    /// to lodPixels), @c free = log2(kFreeMergePixels / voxelPixels); both -inf where nothing
    /// merges (--lod 0, a node reaching the near plane). Continuous in the camera.
    struct NodeLevels
    {
        double size, free;
        /// True if some voxel of the node may merge.
        bool merges() const { return size > 0.0; }
    };
    NodeLevels nodeLevels(const openvdb::Coord& min, int dim) const;

    /// The continuous level of each 2^3 block of a leaf node (kBlocks, blockOf order), which
    /// all its voxels take, from the node's sanitised values @a density (kLeafSize, in offset
    /// order, 0 where inactive or skipped): min(size, max(smooth, free)) clamped to
    /// [0, kMaxLevel], where smooth is the highest level L whose blocks of levels 1..L around
    /// the voxels are all smooth (smoothBlock). Continuous in the camera: smooth depends on the
    /// values alone.
    void blockLevels(const float* density, const NodeLevels& node, float* levels) const;

    /// A continuous level split in two: a voxel's value goes to its block of level @c level
    /// with share 1 - @c upper and to its block of level + 1 with share @c upper.
    struct Split
    {
        int level;
        double upper;
    };
    static Split split(float level)
    {
        const int l = std::min(int(level), kMaxLevel);
        return {l, double(level) - double(l)};
    }

    /// True if a block of @a block voxels a side whose values lie in [lo, hi] merges within
    /// --lod-error: the transmittance through any depth k of the block, from one voxel to all
    /// of it along a lattice axis, differs by at most lodError between a column of its least
    /// and one of its densest value, max_k exp(-s lo k) - exp(-s hi k) with s the extinction,
    /// in every channel. (Across the whole block alone, dense blocks, opaque whatever their
    /// values, would merge and blur the surface they show.)
    bool smoothBlock(float lo, float hi, int block) const;

    /// Lattice step (voxels, a power of two <= @a maxLattice) for surface kernels over the
    /// whole grid: the largest whose spacing projects to at most lodPixels / 4 pixels at every
    /// leaf node's nearest point (one step for all, so that neighbouring discs are alike).
    /// 1 = one kernel per voxel.
    int surfaceLattice(int maxLattice) const;

    /// Screen size in pixels of one voxel's longest axis at the node's nearest point (+inf
    /// when the node reaches the eye's side of the near plane).
    double voxelPixels(const openvdb::Coord& min, int dim) const;

private:
    const GridSource::Impl& mGrid;
    Camera mCamera;
    double mMaxPixels, mMaxError, mExtinction[3];
    double mLatticePixels, mWidestLattice;
};

} // namespace detail
} // namespace vdb_ewa
