/// @file dense_block.h
/// @brief A box of a tree's values copied into a dense array, leaf node by leaf node: a probe
///        per 8^3 node the box overlaps instead of an accessor lookup per voxel.
#pragma once

#include "support/openvdb.h"

#include <algorithm>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// block[((x - lo.x) * side + y - lo.y) * side + z - lo.z] = the tree's value at (x, y, z), for the
/// cube of @a side voxels from @a lo: the same values as the accessor's getValue (the leaves'
/// stored values, active or not; a tile's value; the background).
template <typename TreeT, typename T>
void readDenseBlock(openvdb::tree::ValueAccessor<const TreeT>& acc, const openvdb::Coord& lo, int side, std::vector<T>& block)
{
    using LeafT = typename TreeT::LeafNodeType;
    constexpr int kDim = int(LeafT::DIM);
    block.resize(std::size_t(side) * std::size_t(side) * std::size_t(side));
    const openvdb::Coord hi = lo.offsetBy(side - 1);
    const openvdb::Coord first = lo & ~(kDim - 1);
    for (int lx = first.x(); lx <= hi.x(); lx += kDim)
        for (int ly = first.y(); ly <= hi.y(); ly += kDim)
            for (int lz = first.z(); lz <= hi.z(); lz += kDim) {
                const openvdb::Coord origin(lx, ly, lz);
                const openvdb::Coord a = openvdb::Coord::maxComponent(origin, lo);
                const openvdb::Coord b = openvdb::Coord::minComponent(origin.offsetBy(kDim - 1), hi);
                const LeafT* leaf = acc.probeConstLeaf(origin);
                const T tile = leaf ? T() : T(acc.getValue(origin));
                for (int x = a.x(); x <= b.x(); ++x)
                    for (int y = a.y(); y <= b.y(); ++y) {
                        T* row = &block[std::size_t(((x - lo.x()) * side + y - lo.y()) * side + a.z() - lo.z())];
                        if (!leaf) {
                            std::fill(row, row + (b.z() - a.z() + 1), tile);
                            continue;
                        }
                        const openvdb::Index offset = LeafT::coordToOffset(openvdb::Coord(x, y, a.z()));
                        for (int z = 0; z <= b.z() - a.z(); ++z) row[z] = T(leaf->getValue(offset + openvdb::Index(z)));
                    }
            }
}

} // namespace detail
} // namespace vdb_ewa
