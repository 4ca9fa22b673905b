/// @file surface_extraction.cpp
#include "source/surface_extraction.h"

#include "source/material_color.h"
#include "support/dense_block.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace vdb_ewa {
namespace detail {
namespace {

/// Neighbours whose normals turn by more than this (cos 40 degrees) across a convex crease cut
/// a kernel's disc; smoother turns leave it whole. At 30 degrees noisy shallow creases of a
/// scanned model opened pinpricks; at 45 the rounded kernels of a cube's edges (exactly 45)
/// escaped their clips (docs/equations.md#surface-coverage).
constexpr double kCreaseCos = 0.766044443118978;

/// The clip lines stand this many voxels in front of the neighbour's plane: the kernels'
/// centres and normals come from a sampled field and do not meet exactly at a crease; where
/// neighbours' planes meet at a shallow angle the error along the plane grows as 1/sin(angle).
constexpr double kCreaseMargin = 0.1;

/// The line of kernel a's tangent plane where neighbour b's tangent plane cuts it, when b lies
/// across a convex crease (turned by more than 40 degrees, a's centre behind b's plane): the
/// disc's part in front of b's plane overhangs the surface (a cube's faces past its edges).
/// False for smooth turns, concave creases (a's centre in front of b's plane) and the far side
/// of thin parts (normals more than 96 degrees apart).
bool creaseClip(const SurfaceKernel& a, const SurfaceKernel& b, double spacing, DiscClip& clip)
{
    const double turn = glm::dot(a.normal, b.normal);
    if (turn >= kCreaseCos || turn < -0.1) return false;
    const double offset = glm::dot(b.normal, b.pWorld - a.pWorld); // a's centre is this far behind b's plane
    if (offset < -0.05 * spacing) return false;
    const Vec3d across = b.normal - turn * a.normal; // b's normal in a's tangent plane
    const double length = glm::length(across);
    if (!(length > 1e-6)) return false;
    clip.direction = glm::vec3(across / length);
    clip.distance = float((std::max(offset, 0.0) + kCreaseMargin * spacing) / length);
    return true;
}

/// Clips along the same direction (within 26 degrees) cut along the same crease: kernels of the
/// same face, or of the rounded edge between: keep the nearest.
void mergeClip(std::vector<DiscClip>& clips, const DiscClip& clip)
{
    for (DiscClip& c : clips) {
        if (glm::dot(c.direction, clip.direction) > 0.9f) {
            if (clip.distance < c.distance) c = clip;
            return;
        }
    }
    clips.push_back(clip);
}

/// Whether @a u lies in the cone of @a u1 and @a u2 (all in one tangent plane, unit).
bool inCone(const glm::vec3& u, const glm::vec3& u1, const glm::vec3& u2)
{
    const float c = glm::dot(u1, u2);
    if (c < -0.95f || c > 0.95f) return false;
    // u = a u1 + b u2: solve the 2x2 normal equations.
    const float p = glm::dot(u, u1), q = glm::dot(u, u2), det = 1.0f - c * c;
    const float a = (p - c * q) / det, b = (q - c * p) / det;
    return a > 0.0f && b > 0.0f;
}

/// A kernel's clips: at a corner, the faces' clips meet at the corner and the clip of the
/// corner's own (rounded) kernels, whose direction lies between theirs, only chamfers it by
/// the error of their positions: clips inside the cone of two others are dropped. Then the
/// (at most three) nearest are kept.
void chooseClips(const std::vector<DiscClip>& candidates, std::vector<DiscClip>& kept, SurfaceKernel& k)
{
    kept.clear();
    for (std::size_t i = 0; i < candidates.size(); ++i) {
        bool between = false;
        for (std::size_t j = 0; j < candidates.size() && !between; ++j)
            for (std::size_t l = j + 1; l < candidates.size() && !between; ++l) {
                between = j != i && l != i && inCone(candidates[i].direction, candidates[j].direction, candidates[l].direction);
            }
        if (!between) kept.push_back(candidates[i]);
    }
    std::sort(kept.begin(), kept.end(), [](const DiscClip& x, const DiscClip& y) { return x.distance < y.distance; });
    k.clipCount = int(std::min(kept.size(), k.clips.size()));
    for (int i = 0; i < k.clipCount; ++i) k.clips[std::size_t(i)] = kept[std::size_t(i)];
}

/// A kernel's disc must reach its neighbours' (Botsch et al. 2005: the radius from the
/// neighbourhood), no farther: a disc overhangs a curved silhouette by radius^2 / (2 x the
/// curvature radius). The distance to the kNeighboursCovered-th nearest neighbour on the same
/// sheet, tangentially, at most @a maxRadius (3 sigma); @a maxRadius where there are fewer.
/// @a squaredDistances: the neighbours' squared tangential distances (reordered).
constexpr std::size_t kNeighboursCovered = 8;
double discRadiusFrom(std::vector<double>& squaredDistances, double maxRadius)
{
    if (squaredDistances.size() < kNeighboursCovered) return maxRadius;
    std::nth_element(squaredDistances.begin(), squaredDistances.begin() + std::ptrdiff_t(kNeighboursCovered - 1), squaredDistances.end());
    return std::min(maxRadius, std::sqrt(squaredDistances[kNeighboursCovered - 1]));
}

/// What each kernel takes from its neighbours on the surface (index offsets up to @a radius):
/// Area per kernel = 1 / (density of kernels on the surface around it): the sum over the
/// neighbours j on the same sheet (normal offset < 1.5 voxels, normals within 72 degrees) of
/// the tangential Gaussian G_sigma(p_j - p_k). Then sum_k area_k G_sigma(u - u_k) ~ 1 on the
/// surface (a partition of unity), however many voxels represent each piece of it.
/// Disc radius: discRadiusFrom the same neighbours' tangential distances.
/// Disc clips: the nearest convex creases within the disc (creaseClip, chooseClips).
/// Only for the kernels @a drawn (all if empty); the others are still neighbours.
void relateNeighbours(LargeArray<SurfaceKernel>& kernels, const std::vector<openvdb::Coord>& voxels, double sigma,
    double spacing, int radius, const std::function<bool(const SurfaceKernel&)>& drawn)
{
    // The kernels at each coordinate, which are consecutive: the first's index x 4 + count - 1
    // (one a voxel; up to kMaxSheetsPerBlock a level-of-detail block). The memory budget keeps
    // the kernels far below 2^29.
    static_assert(kMaxSheetsPerBlock <= 4, "two bits of the index hold the count");
    openvdb::Int32Grid index(-1);
    {
        auto acc = index.getAccessor();
        for (std::size_t i = 0; i < voxels.size(); ++i) {
            if (i > 0 && voxels[i] == voxels[i - 1]) acc.setValueOn(voxels[i], acc.getValue(voxels[i]) + 1);
            else acc.setValueOn(voxels[i], int(4 * i));
        }
    }
    const double twoPiS2 = 6.283185307179586 * sigma * sigma, inv2S2 = 0.5 / (sigma * sigma);
    const double maxNormalOffset = 1.5 * spacing;
    const double discRadius = kDiscRadiusSigmas * sigma;
    // The kernels come leaf by leaf (8^3 voxels): each leaf's neighbourhood, the leaf and
    // @a radius voxels around it, is read into a dense block once (readDenseBlock: 27 leaf
    // nodes for radius 2, instead of 125 lookups a kernel).
    std::vector<std::size_t> leafStarts;
    for (std::size_t k = 0; k < voxels.size(); ++k) {
        if (k == 0 || (voxels[k] & ~7) != (voxels[k - 1] & ~7)) leafStarts.push_back(k);
    }
    leafStarts.push_back(voxels.size());
    const int side = 8 + 2 * radius;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leafStarts.size() - 1, 16), [&](const tbb::blocked_range<std::size_t>& r) {
        auto acc = index.getConstAccessor();
        std::vector<int> block(std::size_t(side) * std::size_t(side) * std::size_t(side));
        std::vector<double> distances; // squared tangential distances to the neighbours on the same sheet
        std::vector<DiscClip> candidates, kept;
        for (std::size_t leaf = r.begin(); leaf < r.end(); ++leaf) {
            const openvdb::Coord corner = (voxels[leafStarts[leaf]] & ~7).offsetBy(-radius);
            readDenseBlock(acc, corner, side, block);
            for (std::size_t k = leafStarts[leaf]; k < leafStarts[leaf + 1]; ++k) {
                if (drawn && !drawn(kernels[k])) continue; // area 0, no disc: not drawn
                // The neighbours read only the kernels' centres and normals: the other fields
                // are written in place.
                SurfaceKernel& a = kernels[k];
                double density = 0.0;
                distances.clear();
                candidates.clear();
                const openvdb::Coord c = voxels[k] - corner; // >= radius along each axis
                for (int i = -radius; i <= radius; ++i)
                    for (int j = -radius; j <= radius; ++j)
                        for (int l = -radius; l <= radius; ++l) {
                            const int entry = block[std::size_t(((c.x() + i) * side + c.y() + j) * side + c.z() + l)];
                            if (entry < 0) continue;
                            for (int other = entry / 4; other <= entry / 4 + entry % 4; ++other) {
                                const SurfaceKernel& b = kernels[std::size_t(other)];
                                const Vec3d d = b.pWorld - a.pWorld;
                                const double along = glm::dot(d, a.normal);
                                const double turn = glm::dot(a.normal, b.normal);
                                DiscClip clip;
                                if (turn < kCreaseCos && creaseClip(a, b, spacing, clip) && clip.distance < discRadius) {
                                    mergeClip(candidates, clip);
                                }
                                if (std::abs(along) > maxNormalOffset || turn < 0.3) continue; // another sheet
                                const double tangential2 = std::max(0.0, glm::dot(d, d) - along * along);
                                density += double(std::exp(float(-tangential2 * inv2S2))); // float: 1e-7 of the area
                                if (other != int(k)) distances.push_back(tangential2);
                            }
                        }
                a.area = twoPiS2 / density; // density includes the kernel itself: > 0
                chooseClips(candidates, kept, a);
                a.discRadius = discRadiusFrom(distances, discRadius);
            }
        }
    });
}

/// Level of detail: of one leaf's kernels (@a voxels, in the leaf), each block of @a s^3 voxels
/// (s divides the leaf's 8) keeps, for each sheet through it, the kernel nearest the block's
/// centre, and gives it the block's coordinates (voxel / s). Kernels whose normals turn by
/// more than 40 degrees (kCreaseCos) are on different sheets: a crease's two faces, a thin
/// plate's two sides; keeping both keeps the creases' clips and the plate's far side. At most
/// kMaxSheetsPerBlock sheets a block, in the order they come; kept kernels are grouped by block.
void thinToLattice(std::vector<SurfaceKernel>& kernels, std::vector<openvdb::Coord>& voxels, int s, const GridSource::Impl& grid)
{
    constexpr int kDim = int(openvdb::FloatTree::LeafNodeType::DIM);
    const int n = kDim / s;
    int shift = 0; // s = 2^shift
    while ((1 << shift) < s) ++shift;
    struct Sheet
    {
        int kernel;
        double distance; // squared, to the block's centre
    };
    std::vector<std::array<Sheet, kMaxSheetsPerBlock>> sheets(std::size_t(n * n * n));
    std::vector<int> counts(sheets.size(), 0);
    auto blockOf = [&](const openvdb::Coord& v) {
        const openvdb::Coord b = (v & (kDim - 1)) >> std::size_t(shift); // the block, within the leaf
        return std::size_t((b.x() * n + b.y()) * n + b.z());
    };
    for (std::size_t i = 0; i < kernels.size(); ++i) {
        const std::size_t b = blockOf(voxels[i]);
        const openvdb::Coord origin = voxels[i] & ~(s - 1); // the block's first voxel
        const Vec3d centre = grid.indexToWorld(Vec3d(origin.x(), origin.y(), origin.z()) + Vec3d(0.5 * (s - 1)));
        const Vec3d d = kernels[i].pWorld - centre;
        const Sheet candidate{int(i), glm::dot(d, d)};
        int c = 0;
        while (c < counts[b] && glm::dot(kernels[std::size_t(sheets[b][std::size_t(c)].kernel)].normal, kernels[i].normal) < kCreaseCos) ++c;
        if (c == counts[b]) {
            if (c < kMaxSheetsPerBlock) sheets[b][std::size_t(counts[b]++)] = candidate;
        } else if (candidate.distance < sheets[b][std::size_t(c)].distance) {
            sheets[b][std::size_t(c)] = candidate;
        }
    }
    std::vector<SurfaceKernel> keptKernels;
    std::vector<openvdb::Coord> keptVoxels;
    for (std::size_t b = 0; b < sheets.size(); ++b)
        for (int c = 0; c < counts[b]; ++c) {
            const std::size_t k = std::size_t(sheets[b][std::size_t(c)].kernel);
            keptKernels.push_back(kernels[k]);
            keptVoxels.push_back(voxels[k] >> std::size_t(shift)); // arithmetic shift: floor(voxel / s)
        }
    kernels.swap(keptKernels);
    voxels.swap(keptVoxels);
}

} // namespace

SurfaceSet extractSurfaceKernels(const GridSource::Impl& grid, const SurfaceRequest& request, Progress* progress)
{
    const double isovalue = request.isovalue, kernelSigma = request.kernelSigma, reach = request.reach;
    const bool outwardDecreasing = request.outwardDecreasing;
    const int s = request.lattice;
    SurfaceSet out;
    const openvdb::FloatTree& tree = grid.grid->tree();
    const auto& xform = grid.grid->transform();
    out.lattice = s;
    out.spacing = grid.voxelLength * s;
    out.sigma = kernelSigma * out.spacing;
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
    // Neighbours within two lattice steps: at sigma = 0.55 steps a kernel two steps away along
    // the surface adds 0.14 % of a kernel's own weight (duplicates across layers, up to two
    // steps apart along the normal, are inside). Wider kernels look farther.
    const int radius = std::max(2, int(std::ceil(3.5 * kernelSigma)));
    const double leafMargin = 0.5 + (radius + 1) * s; // index units: the neighbours' reach, and a step for the Newton offset
    setUnits(progress, leaves.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        openvdb::tree::ValueAccessor<const openvdb::FloatTree> acc(tree);
        MaterialColor color(grid);
        constexpr int kBlockSide = 10;
        constexpr std::size_t kAxisStride[3] = {kBlockSide * kBlockSide, kBlockSide, 1};
        std::vector<float> block;
        for (std::size_t l = r.begin(); l < r.end(); ++l) {
            if (request.leafMayBeSeen) {
                const openvdb::Vec3d o = leaves[l]->origin().asVec3d();
                const openvdb::BBoxd world = xform.indexToWorld(openvdb::BBoxd(o - openvdb::Vec3d(leafMargin), o + openvdb::Vec3d(7.0 + leafMargin)));
                if (!request.leafMayBeSeen(Vec3d(world.min().x(), world.min().y(), world.min().z()),
                        Vec3d(world.max().x(), world.max().y(), world.max().z()))) {
                    continue;
                }
            }
            // The leaf and a voxel around it, for the 6-neighbourhoods.
            const openvdb::Coord corner = leaves[l]->origin().offsetBy(-1);
            readDenseBlock(acc, corner, kBlockSide, block);
            for (auto it = leaves[l]->cbeginValueOn(); it; ++it) {
                const double d = double(*it) - isovalue;
                if (!std::isfinite(d)) continue;
                const openvdb::Coord ijk = it.getCoord();
                const openvdb::Coord local = ijk - corner;
                const std::size_t centre = std::size_t((local.x() * kBlockSide + local.y()) * kBlockSide + local.z());
                // Index-space gradient by central differences (the band's sign is kept by the
                // background value outside it).
                Vec3d g;
                bool crosses = d == 0.0; // the surface passes between this voxel and a neighbour
                for (int a = 0; a < 3; ++a) {
                    const double vLo = block[centre - kAxisStride[a]], vHi = block[centre + kAxisStride[a]];
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
                if (std::max({std::abs(stepIndex.x), std::abs(stepIndex.y), std::abs(stepIndex.z)}) > reach) continue;
                SurfaceKernel k;
                k.normal = (outwardDecreasing ? -1.0 : 1.0) * gWorld / std::sqrt(g2);
                k.pWorld = grid.indexToWorld(Vec3d(c.x(), c.y(), c.z())) + stepWorld;
                k.area = 0.0; // relateNeighbours
                k.albedo = color.at(k.pWorld);
                perLeaf[l].push_back(k);
                perLeafVoxels[l].push_back(ijk);
            }
            if (s > 1) thinToLattice(perLeaf[l], perLeafVoxels[l], s, grid);
        }
        advance(progress, r.size());
    });
    // The leaves' kernels, in leaf order.
    std::vector<std::size_t> firstOfLeaf(perLeaf.size() + 1, 0);
    for (std::size_t l = 0; l < perLeaf.size(); ++l) firstOfLeaf[l + 1] = firstOfLeaf[l] + perLeaf[l].size();
    out.kernels.resize(firstOfLeaf.back());
    std::vector<openvdb::Coord> voxels(firstOfLeaf.back());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, perLeaf.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t l = r.begin(); l < r.end(); ++l) {
            std::copy(perLeaf[l].begin(), perLeaf[l].end(), out.kernels.begin() + std::ptrdiff_t(firstOfLeaf[l]));
            std::copy(perLeafVoxels[l].begin(), perLeafVoxels[l].end(), voxels.begin() + std::ptrdiff_t(firstOfLeaf[l]));
            std::vector<SurfaceKernel>().swap(perLeaf[l]);
        }
    });
    relateNeighbours(out.kernels, voxels, out.sigma, out.spacing, radius, request.drawn);
    return out;
}

} // namespace detail
} // namespace vdb_ewa
