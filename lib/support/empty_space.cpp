/// @file empty_space.cpp
#include "support/empty_space.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vdb_ewa {
namespace detail {

double boxExit(const Vec3d& o, const Vec3d& d, const Vec3d& lo, const Vec3d& hi)
{
    double tExit = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
        if (d[a] > 0.0) tExit = std::min(tExit, (hi[a] - o[a]) / d[a]);
        else if (d[a] < 0.0) tExit = std::min(tExit, (lo[a] - o[a]) / d[a]);
    }
    return tExit;
}

bool boxClip(const Vec3d& o, const Vec3d& d, const Vec3d& lo, const Vec3d& hi, double& t0, double& t1)
{
    t0 = -std::numeric_limits<double>::infinity();
    t1 = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
        if (d[a] == 0.0) {
            if (o[a] < lo[a] || o[a] > hi[a]) return false;
            continue;
        }
        double ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    return t0 <= t1;
}

double EmptySpaceSkipper::emptyExit(const Vec3d& p, const Vec3d& d)
{
    const openvdb::Coord ijk = openvdb::Coord::floor(openvdb::Vec3d(p.x, p.y, p.z));
    const int depth = mAccessor.getValueDepth(ijk);
    const int leafDepth = int(openvdb::FloatTree::DEPTH) - 1;
    if (depth == leafDepth) return 0.0;
    if (mAccessor.isValueOn(ijk) || mAccessor.getValue(ijk) != 0.0f) return 0.0;
    // Side of the empty node: root children 4096, then 128, then 8 (5-4-3 tree); -1 is background.
    static const int kDims[] = {4096, 4096, 128, 8};
    const int dim = kDims[std::clamp(depth + 1, 0, 3)];
    const Vec3d lo(double(ijk.x() & ~(dim - 1)), double(ijk.y() & ~(dim - 1)), double(ijk.z() & ~(dim - 1)));
    // Voxels read: floor(p) - margin .. floor(p) + 1 + margin, all inside [lo, lo + dim - 1].
    const Vec3d safeLo = lo + double(mMargin);
    const Vec3d safeHi = lo + double(dim - 1 - mMargin);
    for (int a = 0; a < 3; ++a) {
        if (p[a] < safeLo[a] || p[a] >= safeHi[a]) return 0.0;
    }
    const double t = boxExit(p, d, safeLo, safeHi);
    return (t > 0.0 && std::isfinite(t)) ? t : 0.0;
}

} // namespace detail
} // namespace vdb_ewa
