/// @file quasi_interpolation.cpp
#include "source/quasi_interpolation.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>

namespace vdb_ewa {
namespace detail {
namespace {

const openvdb::Coord kFaceNeighbours[6] = {openvdb::Coord(-1, 0, 0), openvdb::Coord(1, 0, 0), openvdb::Coord(0, -1, 0),
    openvdb::Coord(0, 1, 0), openvdb::Coord(0, 0, -1), openvdb::Coord(0, 0, 1)};

/// c = v + alpha sum_axes (2 v - v_- - v_+) at @a ijk, values from the field.
template <typename Accessor>
float prefiltered(Accessor& field, const openvdb::Coord& ijk, double alpha)
{
    const double v = double(field.getValue(ijk));
    double laplacian = 0.0;
    for (const openvdb::Coord& d : kFaceNeighbours) laplacian += v - double(field.getValue(ijk + d));
    return float(v + alpha * laplacian);
}

} // namespace

double quasiInterpolationAlpha(double sigma)
{
    return std::max(0.0, 0.5 * sigma * sigma - 1.0 / 12.0);
}

std::uint64_t quasiInterpolate(const GridSource::Impl& grid, double alpha, KernelSet& set, const openvdb::MaskGrid* sampled,
    const UnitKernelRule* units)
{
    if (!(alpha > 0.0)) return 0;
    LargeArray<Kernel>& kernels = set.kernels;
    // Where the unit kernels are: the set's own, or the whole grid's (units).
    openvdb::MaskGrid mask(false);
    if (!units) {
        auto acc = mask.getAccessor();
        for (const Kernel& k : kernels) {
            if (isUnitKernel(k)) acc.setValueOn(voxelOf(k));
        }
    }
    const std::size_t n = kernels.size();
    const std::size_t grain = 4096, chunks = (n + grain - 1) / grain;
    std::vector<std::vector<Kernel>> halos(chunks);
    std::vector<float> weights(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& range) {
        auto field = grid.field->getConstAccessor();
        auto active = grid.grid->getConstAccessor();
        auto inMask = mask.getConstAccessor();
        const openvdb::MaskGrid none(false);
        auto isSampled = (sampled ? *sampled : none).getConstAccessor();
        std::optional<UnitKernelProbe> probe;
        if (units) probe.emplace(grid, units->settings, units->lod);
        const auto isUnit = [&](const openvdb::Coord& c) { return probe ? probe->isUnit(c) : inMask.isValueOn(c); };
        for (std::size_t c = range.begin(); c < range.end(); ++c) {
            for (std::size_t i = c * grain; i < std::min(n, (c + 1) * grain); ++i) {
                const Kernel& k = kernels[i];
                weights[i] = k.density;
                if (!isUnitKernel(k)) continue;
                const openvdb::Coord ijk = voxelOf(k);
                // A voxel the level of detail shares with a block carries that share of its
                // value (kernel_extraction.cpp); its weight and its halo take the same share
                // (1 exactly elsewhere: the kernel holds the field's value).
                const float value = field.getValue(ijk);
                const double share = value > 0.0f ? double(k.density) / double(value) : 1.0;
                weights[i] = float(share * double(prefiltered(field, ijk, alpha)));
                for (const openvdb::Coord& d : kFaceNeighbours) {
                    const openvdb::Coord h = ijk + d;
                    // A halo voxel: inactive (active ones have kernels of their own: voxels,
                    // merged blocks, tiles) and not sampled by refinement, added once, by its
                    // first unit-kernel neighbour.
                    if (isUnit(h) || active.isValueOn(h) || isSampled.isValueOn(h)) continue;
                    openvdb::Coord first = ijk;
                    for (const openvdb::Coord& e : kFaceNeighbours) {
                        if (isUnit(h + e)) {
                            first = h + e;
                            break;
                        }
                    }
                    if (first != ijk) continue;
                    const float w = float(share * double(prefiltered(field, h, alpha)));
                    if (w != 0.0f) halos[c].push_back({Vec3d(h.x(), h.y(), h.z()), w, 1.0f});
                }
            }
        }
    });
    for (std::size_t i = 0; i < n; ++i) kernels[i].density = weights[i];
    std::uint64_t added = 0;
    for (const auto& h : halos) {
        kernels.insert(kernels.end(), h.begin(), h.end());
        added += h.size();
    }
    return added;
}

} // namespace detail
} // namespace vdb_ewa
