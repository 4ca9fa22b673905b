/// @file material_color.cpp
#include "source/material_color.h"

#include "support/openvdb_tools.h"

#include <tbb/parallel_for.h>

#include <cmath>

namespace vdb_ewa {
namespace detail {

MaterialColor::MaterialColor(const GridSource::Impl& grid) : mGrid(grid)
{
    if (grid.color) mAccessor.emplace(grid.color->getConstAccessor());
}

Vec3d MaterialColor::at(const Vec3d& pWorld)
{
    if (!mAccessor) return Vec3d(1.0);
    const openvdb::Vec3s c = openvdb::tools::BoxSampler::sample(
        *mAccessor, mGrid.color->transform().worldToIndex(openvdb::Vec3d(pWorld.x, pWorld.y, pWorld.z)));
    Vec3d out;
    for (int a = 0; a < 3; ++a) out[a] = std::isfinite(c[a]) && c[a] > 0.0f ? double(c[a]) : 0.0;
    return out;
}

Vec3d workingColor(const Mat3d& inputToWorking, const Vec3d& color)
{
    return glm::max(inputToWorking * color, Vec3d(0.0));
}

std::vector<Rgb> kernelColors(const GridSource::Impl& grid, const KernelSet& kernels, const Mat3d& inputToWorking)
{
    std::vector<Rgb> out;
    if (!grid.color) return out;
    out.resize(kernels.kernels.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
        MaterialColor color(grid);
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3d c = workingColor(inputToWorking, color.at(grid.indexToWorld(kernels.kernels[i].pIndex)));
            out[i] = Rgb{float(c.x), float(c.y), float(c.z)};
        }
    });
    return out;
}

} // namespace detail
} // namespace vdb_ewa
