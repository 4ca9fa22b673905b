/// @file level_of_detail.h
/// @brief Level of detail: where voxels project smaller than --lod pixels, blocks of 2^L
///        voxels a side become one kernel of spacing 2^L (docs/equations.md#level-of-detail).
#pragma once

#include <vdb_ewa/camera.h>
#include <vdb_ewa/grid_source.h>

#include "support/openvdb.h"

namespace vdb_ewa {
namespace detail {

class LevelOfDetail
{
public:
    /// @param maxPixels largest screen size (pixels) of a merged kernel's spacing; 0 disables merging
    LevelOfDetail(const GridSource::Impl& grid, const Camera& camera, double maxPixels);

    /// Block size (voxels a side, a power of two <= @a dim) for the node whose voxels span
    /// [min, min + dim - 1]: the largest whose spacing, seen from the node's nearest point,
    /// projects to at most maxPixels pixels. 1 = one kernel per voxel.
    int blockSize(const openvdb::Coord& min, int dim) const;

    /// Lattice step (voxels, a power of two <= @a maxLattice) for surface kernels over the
    /// whole grid: the largest whose spacing projects to at most maxPixels / 4 pixels at every
    /// leaf node's nearest point (one step for all, so that neighbouring discs are alike).
    /// 1 = one kernel per voxel.
    int surfaceLattice(int maxLattice) const;

    /// Screen size in pixels of one voxel's longest axis at the node's nearest point (+inf
    /// when the node reaches the eye's side of the near plane).
    double voxelPixels(const openvdb::Coord& min, int dim) const;

private:
    const GridSource::Impl& mGrid;
    Camera mCamera;
    double mMaxPixels;
};

} // namespace detail
} // namespace vdb_ewa
