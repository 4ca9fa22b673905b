/// @file kernel_refinement.cpp
#include "source/kernel_refinement.h"

#include "support/openvdb_morphology.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vdb_ewa {
namespace detail {
namespace {

constexpr int kMaxSamples = kMaxFine; // a cell's n samples a side and one beyond each end

/// Relative spread below which a voxel's neighbourhood counts as uniform (not refined).
constexpr float kUniformTolerance = 1e-3f;

/// The field's values around @a ijk (its 3^3 neighbourhood) agree to kUniformTolerance.
template <typename Accessor>
bool uniformNeighbourhood(Accessor& field, const openvdb::Coord& ijk)
{
    const float v = field.getValue(ijk);
    for (int x = -1; x <= 1; ++x)
        for (int y = -1; y <= 1; ++y)
            for (int z = -1; z <= 1; ++z) {
                if (std::abs(field.getValue(ijk.offsetBy(x, y, z)) - v) > kUniformTolerance * v) return false;
            }
    return true;
}

/// The fine lattice along one axis of a voxel: the voxel holds the samples at offsets a / n,
/// a = 0 .. n - 1, from its centre (the lattice contains the voxel centres, where the trilinear
/// field's pieces meet, so the samples' piecewise-linear interpolant is the field itself);
/// a = -1 and n are the neighbours the prefilter reads (index a + 1). With their trilinear
/// weights on the voxel's neighbours -1, 0, +1.
struct FineAxis
{
    int n;
    double offset[kMaxSamples];
    double weight[kMaxSamples][3];

    explicit FineAxis(int n_) : n(n_)
    {
        for (int a = -1; a <= n; ++a) {
            const double p = double(a) / n; // -1/n .. 1
            offset[a + 1] = p;
            for (int d = -1; d <= 1; ++d) weight[a + 1][d + 1] = std::max(0.0, 1.0 - std::abs(p - d));
        }
    }
};

/// Append the kernels of the cell @a ijk: the trilinear field of its 3^3 neighbourhood @a v
/// sampled on the fine lattice (Eq. 8: one kernel a sample), samples below @a cutoff read as 0,
/// times the sampled voxels' @a share (shareOf), weights prefiltered with @a alpha.
void sampleVoxel(const openvdb::Coord& ijk, const float (&v)[3][3][3], const FineAxis& axis, double alpha, double cutoff,
    const double (&share)[kMaxFine][kMaxFine][kMaxFine], std::vector<Kernel>& out)
{
    const int n = axis.n, m = n + 2;
    // Separable trilinear interpolation: z, then y, then x.
    double a[3][3][kMaxSamples], b[3][kMaxSamples][kMaxSamples], f[kMaxSamples][kMaxSamples][kMaxSamples];
    for (int x = 0; x < 3; ++x)
        for (int y = 0; y < 3; ++y)
            for (int k = 0; k < m; ++k)
                a[x][y][k] = v[x][y][0] * axis.weight[k][0] + v[x][y][1] * axis.weight[k][1] + v[x][y][2] * axis.weight[k][2];
    for (int x = 0; x < 3; ++x)
        for (int j = 0; j < m; ++j)
            for (int k = 0; k < m; ++k)
                b[x][j][k] = a[x][0][k] * axis.weight[j][0] + a[x][1][k] * axis.weight[j][1] + a[x][2][k] * axis.weight[j][2];
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j)
            for (int k = 0; k < m; ++k)
                f[i][j][k] = b[0][j][k] * axis.weight[i][0] + b[1][j][k] * axis.weight[i][1] + b[2][j][k] * axis.weight[i][2];
    // Samples below --cutoff read as 0, as the reference's and vdb_render's samples do; each
    // carries the sampled voxels' share of the field.
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j)
            for (int k = 0; k < m; ++k) f[i][j][k] = f[i][j][k] < cutoff ? 0.0 : f[i][j][k] * share[i][j][k];
    const float spacing = float(1.0 / n);
    prefilterFineSamples(n, alpha, [&](int i, int j, int k) { return f[i][j][k]; }, [&](int i, int j, int k, float w) {
        out.push_back({Vec3d(ijk.x() + axis.offset[i], ijk.y() + axis.offset[j], ijk.z() + axis.offset[k]), w, spacing});
    });
}

/// Which unit kernels of @a set to refine at @a n (2) and which to keep (1; 0: not a unit
/// kernel): those of leaf nodes whose voxels span n pixels or more (the fine lattice spans a
/// pixel or more) and that the level of detail leaves whole (its voxels carry a share of
/// their values), where the field is not uniform over the voxel's neighbourhood (there the
/// voxel's own kernel is the field already, to its ripple).
std::vector<std::uint8_t> chooseRefined(const GridSource::Impl& grid, int n, const LevelOfDetail& scale, const KernelSet& set)
{
    std::vector<std::uint8_t> choice(set.kernels.size(), 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, choice.size(), 4096), [&](const tbb::blocked_range<std::size_t>& range) {
        auto field = grid.field->getConstAccessor();
        openvdb::Coord node(std::numeric_limits<int>::max());
        bool large = false;
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            const Kernel& k = set.kernels[i];
            if (!isUnitKernel(k)) continue;
            const openvdb::Coord ijk = voxelOf(k);
            const openvdb::Coord origin(ijk.x() & ~7, ijk.y() & ~7, ijk.z() & ~7);
            if (origin != node) { // kernels are in tree order: one lookup a node
                node = origin;
                large = scale.voxelPixels(origin, 8) >= double(n) && !scale.nodeLevels(origin, 8).merges();
            }
            choice[i] = large && !uniformNeighbourhood(field, ijk) ? 2 : 1;
        }
    });
    return choice;
}

/// The voxels to sample: the refined kernels' and the one-voxel shell where their trilinear
/// field reaches, less voxels that other kernels model (unrefined unit kernels, tiles, merged
/// blocks). Active voxels below @a cutoff are sampled, as the field there is not 0.
void voxelsToSample(const GridSource::Impl& grid, float cutoff, const KernelSet& set,
    const std::vector<std::uint8_t>& choice, openvdb::MaskGrid& sampled)
{
    openvdb::MaskGrid refined(false), kept(false);
    {
        auto refine = refined.getAccessor();
        auto keep = kept.getAccessor();
        for (std::size_t i = 0; i < choice.size(); ++i) {
            if (choice[i]) (choice[i] == 2 ? refine : keep).setValueOn(voxelOf(set.kernels[i]));
        }
    }
    sampled.clear();
    sampled.tree().topologyUnion(refined.tree());
    openvdb::tools::dilateActiveValues(sampled.tree(), 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
    sampled.tree().topologyDifference(kept.tree());
    std::vector<openvdb::Coord> modelled;
    auto active = grid.grid->getConstAccessor();
    auto isRefined = refined.getConstAccessor();
    for (auto it = sampled.cbeginValueOn(); it; ++it) {
        float value = 0.0f;
        if (!isRefined.isValueOn(it.getCoord()) && active.probeValue(it.getCoord(), value) && value >= cutoff) {
            modelled.push_back(it.getCoord());
        }
    }
    auto acc = sampled.getAccessor();
    for (const openvdb::Coord& c : modelled) acc.setValueOff(c);
}

/// The kernels of @a cells, the cells around the voxels of @a sampled (cellsAround), one vector
/// a leaf node of cells (in tree order).
std::vector<std::vector<Kernel>> sampleVoxels(const GridSource::Impl& grid, const openvdb::MaskGrid& sampled,
    const openvdb::MaskGrid& cells, int n, double alpha, float cutoff, Progress* progress)
{
    using MaskLeaf = openvdb::MaskTree::LeafNodeType;
    std::vector<const MaskLeaf*> leaves;
    leaves.reserve(cells.tree().leafCount());
    cells.tree().getNodes(leaves);
    std::vector<std::vector<Kernel>> perLeaf(leaves.size());
    const FineAxis axis(n);
    const FineTents tents(n);
    setUnits(progress, leaves.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()), [&](const tbb::blocked_range<std::size_t>& range) {
        auto field = grid.field->getConstAccessor();
        auto inSampled = sampled.getConstAccessor();
        double share[kMaxFine][kMaxFine][kMaxFine];
        for (std::size_t l = range.begin(); l < range.end(); ++l) {
            std::vector<Kernel>& out = perLeaf[l];
            for (auto it = leaves[l]->cbeginValueOn(); it; ++it) {
                const openvdb::Coord ijk = it.getCoord();
                float v[3][3][3];
                bool any = false;
                for (int x = 0; x < 3; ++x)
                    for (int y = 0; y < 3; ++y)
                        for (int z = 0; z < 3; ++z) {
                            v[x][y][z] = field.getValue(ijk.offsetBy(x - 1, y - 1, z - 1));
                            any = any || v[x][y][z] != 0.0f;
                        }
                if (!any) continue;
                shareOf(inSampled, ijk, tents, share);
                sampleVoxel(ijk, v, axis, alpha, cutoff, share, out);
            }
        }
        advance(progress, range.size());
    });
    return perLeaf;
}

} // namespace

openvdb::MaskGrid::Ptr cellsAround(const openvdb::MaskGrid& sampled)
{
    auto cells = openvdb::MaskGrid::create(false);
    auto acc = cells->getAccessor();
    for (auto it = sampled.cbeginValueOn(); it; ++it) {
        for (int corner = 0; corner < 8; ++corner) acc.setValueOn(it.getCoord().offsetBy(-(corner & 1), -((corner >> 1) & 1), -((corner >> 2) & 1)));
    }
    return cells;
}

FineTents::FineTents(int n_) : n(n_), m(n_ + 2)
{
    for (int i = 0; i < m; ++i)
        for (int x = 0; x < 4; ++x) weight[i][x] = std::max(0.0, 1.0 - std::abs(double(i - 1) / double(n) - double(x - 1)));
}

void shareOf(const openvdb::MaskGrid::ConstAccessor& sampled, const openvdb::Coord& cell, const FineTents& tents,
    double (&share)[kMaxFine][kMaxFine][kMaxFine])
{
    const int m = tents.m;
    bool on[4][4][4];
    bool all = true;
    for (int x = 0; x < 4; ++x)
        for (int y = 0; y < 4; ++y)
            for (int z = 0; z < 4; ++z) {
                on[x][y][z] = sampled.isValueOn(cell.offsetBy(x - 1, y - 1, z - 1));
                all = all && on[x][y][z];
            }
    if (all) {
        for (int i = 0; i < m; ++i)
            for (int j = 0; j < m; ++j)
                for (int k = 0; k < m; ++k) share[i][j][k] = 1.0;
        return;
    }
    // Separably: z, then y, then x.
    double a[4][4][kMaxFine], b[4][kMaxFine][kMaxFine];
    for (int x = 0; x < 4; ++x)
        for (int y = 0; y < 4; ++y)
            for (int k = 0; k < m; ++k) {
                a[x][y][k] = 0.0;
                for (int z = 0; z < 4; ++z) a[x][y][k] += on[x][y][z] ? tents.weight[k][z] : 0.0;
            }
    for (int x = 0; x < 4; ++x)
        for (int j = 0; j < m; ++j)
            for (int k = 0; k < m; ++k) {
                b[x][j][k] = 0.0;
                for (int y = 0; y < 4; ++y) b[x][j][k] += a[x][y][k] * tents.weight[j][y];
            }
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j)
            for (int k = 0; k < m; ++k) {
                share[i][j][k] = 0.0;
                for (int x = 0; x < 4; ++x) share[i][j][k] += b[x][j][k] * tents.weight[i][x];
            }
}

Refinement refineKernels(const GridSource::Impl& grid, int n, double alpha, float cutoff, const LevelOfDetail& scale,
    KernelSet& set, openvdb::MaskGrid& sampled, Progress* progress, double budget)
{
    sampled.clear();
    Refinement result;
    std::vector<std::uint8_t> choice;
    openvdb::MaskGrid::Ptr cells;
    // The finest lattice whose kernels (at most n^3 a cell around the sampled voxels) fit the budget.
    for (n = std::min(n, kMaxRefinement); n > 1; --n) {
        choice = chooseRefined(grid, n, scale, set);
        voxelsToSample(grid, cutoff, set, choice, sampled);
        cells = cellsAround(sampled);
        if (double(cells->activeVoxelCount()) * n * n * n <= budget) break;
        sampled.clear();
        result.lowered = true;
    }
    if (n <= 1 || sampled.tree().empty()) return result;
    result.n = n;
    result.sampledVoxels = sampled.activeVoxelCount();
    std::vector<std::vector<Kernel>> samples = sampleVoxels(grid, sampled, *cells, n, alpha, cutoff, progress);

    // The kernels that stay (in their order), then the samples (in the voxels' tree order).
    std::size_t total = 0;
    for (std::size_t i = 0; i < choice.size(); ++i) total += choice[i] != 2;
    for (const auto& k : samples) total += k.size();
    LargeArray<Kernel> out;
    out.reserve(total);
    for (std::size_t i = 0; i < choice.size(); ++i) {
        if (choice[i] != 2) out.push_back(set.kernels[i]);
    }
    for (auto& k : samples) {
        out.insert(out.end(), k.begin(), k.end());
        std::vector<Kernel>().swap(k);
    }
    set.kernels = std::move(out);
    return result;
}

} // namespace detail
} // namespace vdb_ewa
