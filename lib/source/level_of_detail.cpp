/// @file level_of_detail.cpp
#include "source/level_of_detail.h"

#include "source/grid_source_impl.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace vdb_ewa {
namespace detail {

LevelOfDetail::LevelOfDetail(const GridSource::Impl& grid, const Camera& camera, double maxPixels)
    : mGrid(grid), mCamera(camera), mMaxPixels(maxPixels)
{
}

double LevelOfDetail::voxelPixels(const openvdb::Coord& min, int dim) const
{
    const auto& xform = mGrid.grid->transform();
    const double half = 0.5 * double(dim - 1);
    const openvdb::Vec3d cIndex(min.x() + half, min.y() + half, min.z() + half);
    const Mat3d a = indexToWorldJacobian(xform, cIndex);
    double axis = 0.0; // world length of the longest index axis
    for (int i = 0; i < 3; ++i) axis = std::max(axis, glm::length(a[i]));
    if (mCamera.projection() == Projection::Orthographic) return axis * mCamera.focalPixels();
    const openvdb::Vec3d w = xform.indexToWorld(cIndex);
    // Nearest depth of the node: its centre's depth less the radius of its bounding sphere.
    const double radius = 0.5 * std::sqrt(3.0) * double(dim) * axis;
    const double depth = mCamera.cameraFromWorldPoint(Vec3d(w.x(), w.y(), w.z())).z - radius;
    if (!(depth > mCamera.near())) return std::numeric_limits<double>::infinity();
    return axis * mCamera.focalPixels() / depth;
}

int LevelOfDetail::blockSize(const openvdb::Coord& min, int dim) const
{
    if (!(mMaxPixels > 0.0)) return 1;
    const double px = voxelPixels(min, dim);
    int s = 1;
    while (2 * s <= dim && double(2 * s) * px <= mMaxPixels) s *= 2;
    return s;
}

/// A surface lattice step projects to at most this share of --lod pixels (half a pixel at the
/// default 2). At a whole pixel (4^3 blocks) the far bunny's IoU against vdb_render's hits fell
/// to 0.9864, against 0.9941 with one kernel per voxel and 0.9928 at half a pixel: the discs
/// overhang curved silhouettes by radius^2 / 2R (docs/equations.md#level-of-detail).
constexpr double kSurfaceLatticeShare = 0.25;

int LevelOfDetail::surfaceLattice(int maxLattice) const
{
    if (!(mMaxPixels > 0.0) || maxLattice < 2) return 1;
    std::vector<const openvdb::FloatTree::LeafNodeType*> leaves;
    mGrid.grid->tree().getNodes(leaves);
    double px = 0.0; // the largest voxel on screen
    for (const auto* leaf : leaves) {
        px = std::max(px, voxelPixels(leaf->origin(), int(openvdb::FloatTree::LeafNodeType::DIM)));
        if (!(2.0 * px <= kSurfaceLatticeShare * mMaxPixels)) return 1; // also +inf: a node at the eye
    }
    int s = 1;
    while (2 * s <= maxLattice && double(2 * s) * px <= kSurfaceLatticeShare * mMaxPixels) s *= 2;
    return s;
}

} // namespace detail
} // namespace vdb_ewa
