/// @file surface_extraction.cpp
#include "source/surface_extraction.h"

#include "source/material_color.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace vdb_ewa {
namespace detail {
namespace {

/// A voxel is kept when its Newton step onto the surface stays within this many voxels of its
/// centre along every index axis. 0.5 (its own cell) would represent each piece of a plane
/// once but leaves gaps where the gradient turns; 1 overlaps the cells and closes them, and
/// the kernels' areas come from their local density (normalizeAreas).
constexpr double kReach = 1.0;

/// Area per kernel = 1 / (density of kernels on the surface around it): the sum over the
/// neighbours j on the same sheet (normal offset < 1.5 voxels, normals within 72 degrees) of
/// the tangential Gaussian G_sigma(p_j - p_k). Then sum_k area_k G_sigma(u - u_k) ~ 1 on the
/// surface (a partition of unity), however many voxels represent each piece of it.
void normalizeAreas(std::vector<SurfaceKernel>& kernels, const std::vector<openvdb::Coord>& voxels, double sigma,
    double voxelLength, int radius)
{
    openvdb::Int32Grid index(-1);
    {
        auto acc = index.getAccessor();
        for (std::size_t i = 0; i < voxels.size(); ++i) acc.setValueOn(voxels[i], int(i));
    }
    const double twoPiS2 = 6.283185307179586 * sigma * sigma, inv2S2 = 0.5 / (sigma * sigma);
    const double maxNormalOffset = 1.5 * voxelLength;
    std::vector<double> areas(kernels.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, kernels.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
        auto acc = index.getConstAccessor();
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const SurfaceKernel& a = kernels[k];
            double density = 0.0;
            const openvdb::Coord c = voxels[k];
            for (int i = -radius; i <= radius; ++i)
                for (int j = -radius; j <= radius; ++j)
                    for (int l = -radius; l <= radius; ++l) {
                        const int other = acc.getValue(c.offsetBy(i, j, l));
                        if (other < 0) continue;
                        const SurfaceKernel& b = kernels[std::size_t(other)];
                        const Vec3d d = b.pWorld - a.pWorld;
                        const double along = glm::dot(d, a.normal);
                        if (std::abs(along) > maxNormalOffset || glm::dot(a.normal, b.normal) < 0.3) continue;
                        density += std::exp(-(glm::dot(d, d) - along * along) * inv2S2) / twoPiS2;
                    }
            areas[k] = 1.0 / density; // density includes the kernel itself: > 0
        }
    });
    for (std::size_t k = 0; k < kernels.size(); ++k) kernels[k].area = areas[k];
}

} // namespace

SurfaceSet extractSurfaceKernels(const GridSource::Impl& grid, double isovalue, double kernelSigma, bool outwardDecreasing,
    Progress* progress)
{
    SurfaceSet out;
    const openvdb::FloatTree& tree = grid.grid->tree();
    const auto& xform = grid.grid->transform();
    out.sigma = kernelSigma * grid.voxelLength;
    out.activeVoxels = tree.activeLeafVoxelCount();
    const openvdb::CoordBBox box = grid.grid->evalActiveVoxelBoundingBox();
    if (!box.empty()) {
        const openvdb::BBoxd world = xform.indexToWorld(box);
        out.boundsMin = Vec3d(world.min().x(), world.min().y(), world.min().z());
        out.boundsMax = Vec3d(world.max().x(), world.max().y(), world.max().z());
    }

    std::vector<const openvdb::FloatTree::LeafNodeType*> leaves;
    tree.getNodes(leaves);
    std::vector<std::vector<SurfaceKernel>> perLeaf(leaves.size());
    std::vector<std::vector<openvdb::Coord>> perLeafVoxels(leaves.size());
    const double reject = 2.0 * grid.voxelLength; // |f - iso| / |grad| beyond this cannot land in reach
    setUnits(progress, leaves.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        openvdb::tree::ValueAccessor<const openvdb::FloatTree> acc(tree);
        MaterialColor color(grid);
        for (std::size_t l = r.begin(); l < r.end(); ++l) {
            for (auto it = leaves[l]->cbeginValueOn(); it; ++it) {
                const double d = double(*it) - isovalue;
                if (!std::isfinite(d)) continue;
                const openvdb::Coord ijk = it.getCoord();
                // Index-space gradient by central differences (the band's sign is kept by the
                // background value outside it).
                Vec3d g;
                bool crosses = d == 0.0; // the surface passes between this voxel and a neighbour
                for (int a = 0; a < 3; ++a) {
                    openvdb::Coord lo = ijk, hi = ijk;
                    lo[a] -= 1;
                    hi[a] += 1;
                    const double vLo = acc.getValue(lo), vHi = acc.getValue(hi);
                    g[a] = 0.5 * (vHi - vLo);
                    crosses = crosses || (vLo - isovalue) * d <= 0.0 || (vHi - isovalue) * d <= 0.0;
                }
                if (!crosses) continue;
                const openvdb::Vec3d c(ijk.x(), ijk.y(), ijk.z());
                const Mat3d A = grid.linear ? grid.indexToWorldLinear : indexToWorldJacobian(xform, c);
                const Mat3d Ainv = glm::inverse(A);
                const Vec3d gWorld = glm::transpose(Ainv) * g; // df/dworld = A^-T df/dindex
                const double g2 = glm::dot(gWorld, gWorld);
                if (!(g2 > 1e-24) || !std::isfinite(g2)) continue;
                if (!(std::abs(d) < reject * std::sqrt(g2))) continue; // the distance estimate |d| / |g|
                // Newton step onto the iso-surface, in world and in index units.
                const Vec3d stepWorld = -d * gWorld / g2;
                const Vec3d stepIndex = Ainv * stepWorld;
                if (std::max({std::abs(stepIndex.x), std::abs(stepIndex.y), std::abs(stepIndex.z)}) > kReach) continue;
                SurfaceKernel k;
                k.normal = (outwardDecreasing ? -1.0 : 1.0) * gWorld / std::sqrt(g2);
                k.pWorld = grid.indexToWorld(Vec3d(c.x(), c.y(), c.z())) + stepWorld;
                k.area = 0.0; // normalizeAreas
                k.albedo = color.at(k.pWorld);
                perLeaf[l].push_back(k);
                perLeafVoxels[l].push_back(ijk);
            }
        }
        advance(progress, r.size());
    });
    std::size_t total = 0;
    for (const auto& v : perLeaf) total += v.size();
    out.kernels.reserve(total);
    std::vector<openvdb::Coord> voxels;
    voxels.reserve(total);
    for (std::size_t l = 0; l < perLeaf.size(); ++l) {
        out.kernels.insert(out.kernels.end(), perLeaf[l].begin(), perLeaf[l].end());
        voxels.insert(voxels.end(), perLeafVoxels[l].begin(), perLeafVoxels[l].end());
    }
    // Neighbours within two voxels: at sigma = 0.55 voxels a kernel two voxels away along the
    // surface adds 0.14 % of a kernel's own weight (duplicates across layers, up to two voxels
    // apart along the normal, are inside). Wider kernels look farther.
    const int radius = std::max(2, int(std::ceil(3.5 * kernelSigma)));
    normalizeAreas(out.kernels, voxels, out.sigma, grid.voxelLength, radius);
    return out;
}

} // namespace detail
} // namespace vdb_ewa
