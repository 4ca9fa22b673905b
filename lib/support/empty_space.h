/// @file empty_space.h
/// @brief Skipping empty space along index-space rays: the tree's inactive, zero-valued nodes.
#pragma once

#include <vdb_ewa/types.h>

#include "support/openvdb.h"

namespace vdb_ewa {
namespace detail {

/// Exit parameter of the ray o + t d from the box [lo, hi] (infinity if d = 0).
double boxExit(const Vec3d& o, const Vec3d& d, const Vec3d& lo, const Vec3d& hi);

/// Entry and exit parameters of the ray o + t d through the box [lo, hi]; false if it misses.
bool boxClip(const Vec3d& o, const Vec3d& d, const Vec3d& lo, const Vec3d& hi, double& t0, double& t1);

/// Finds how far an index-space ray may jump through empty tree nodes. A reconstruction filter
/// reading voxels n with floor(p) - margin <= n <= floor(p) + 1 + margin (margin 0: trilinear)
/// sees only zeros while p stays inside an empty node shrunk accordingly. One per thread: it
/// owns a ValueAccessor.
class EmptySpaceSkipper
{
public:
    EmptySpaceSkipper(const openvdb::FloatGrid& grid, int margin) : mAccessor(grid.tree()), mMargin(margin) {}

    openvdb::FloatGrid::ConstAccessor& accessor() { return mAccessor; }

    /// If @a p lies in an empty node, the parameter along @a d (p + t d) at which it leaves the
    /// node's safe interior; otherwise 0.
    double emptyExit(const Vec3d& p, const Vec3d& d);

private:
    openvdb::FloatGrid::ConstAccessor mAccessor;
    int mMargin;
};

} // namespace detail
} // namespace vdb_ewa
