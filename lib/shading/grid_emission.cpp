/// @file grid_emission.cpp
#include "shading/grid_emission.h"

#include "shading/blackbody.h"
#include "support/openvdb_tools.h"

#include "support/openvdb_morphology.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

namespace vdb_ewa {
namespace detail {
namespace {

/// The blackbody table: 2048 colours from 100 K to 100000 K, evenly in log Kelvin (colder:
/// 100 K's colour, with a luminance of 1e-6 of 1000 K's; hotter: 100000 K's, near the limit).
constexpr double kTableKelvinMin = 100.0, kTableKelvinMax = 1e5;
constexpr int kTableSize = 2048;

/// True if the trilinear cell around @a p has an active voxel of @a temperature at a corner:
/// elsewhere the temperature grid emits nothing, whatever --temperature-offset maps 0 to.
bool inTemperatureCell(const openvdb::FloatGrid::ConstAccessor& temperature, const openvdb::Vec3d& p)
{
    const openvdb::Coord c = openvdb::Coord::floor(p);
    for (int corner = 0; corner < 8; ++corner) {
        if (temperature.isValueOn(c.offsetBy(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1))) return true;
    }
    return false;
}

} // namespace

EmissionModel::EmissionModel(const RenderSettings& settings)
    : mColour(settings.gridEmission.color * settings.gridEmission.intensity), mScale(settings.gridEmission.kelvinScale),
      mOffset(settings.gridEmission.kelvinOffset), mIntensity(settings.gridEmission.blackbodyIntensity)
{
    mTable.resize(kTableSize);
    const Mat3d toWorking = settings.gridEmission.rec709ToWorking * kXyzToLinearRec709;
    for (int i = 0; i < kTableSize; ++i) {
        const double t = double(i) / double(kTableSize - 1);
        const Vec3d rgb = toWorking * blackbodyXyz(kTableKelvinMin * std::pow(kTableKelvinMax / kTableKelvinMin, t));
        mTable[std::size_t(i)] = glm::max(rgb, Vec3d(0.0));
    }
}

double EmissionModel::blackbodyLuminance(double value) const
{
    const double k = kelvin(value);
    return k > 0.0 ? std::min(mIntensity * kBlackbodyUnit * blackbodyRadiance(std::min(k, 1e30)), kMaxRadiance) : 0.0;
}

Vec3d EmissionModel::blackbodyColour(double value) const
{
    const double k = kelvin(value);
    if (!(k > 0.0)) return Vec3d(0.0);
    const double x = std::clamp(std::log(k / kTableKelvinMin) / std::log(kTableKelvinMax / kTableKelvinMin), 0.0, 1.0) * (kTableSize - 1);
    const int i = std::min(int(x), kTableSize - 2);
    const double f = x - double(i);
    return (1.0 - f) * mTable[std::size_t(i)] + f * mTable[std::size_t(i) + 1];
}

namespace {

/// The emission colour per voxel (GridSource::Impl::emissionColor) at index point @a p; white
/// without one.
Vec3d emissionColor(std::optional<openvdb::Vec3SGrid::ConstAccessor>& acc, const openvdb::Vec3d& p)
{
    if (!acc) return Vec3d(1.0);
    const openvdb::Vec3s c = openvdb::tools::BoxSampler::sample(*acc, p);
    return Vec3d(c.x(), c.y(), c.z());
}

} // namespace

EmissionSampler::EmissionSampler(const GridSource::Impl& grid, const EmissionModel* model) : mModel(model)
{
    if (!model) return;
    if (grid.emission) mEmission.emplace(grid.emission->field->getConstAccessor());
    if (grid.emissionColor) mEmissionColor.emplace(grid.emissionColor->getConstAccessor());
    if (grid.temperature) mTemperature.emplace(grid.temperature->field->getConstAccessor());
}

Vec3d EmissionSampler::at(const Vec3d& pIndex)
{
    const openvdb::Vec3d p(pIndex.x, pIndex.y, pIndex.z);
    Vec3d out(0.0);
    if (mEmission) {
        out += mModel->emitted(double(openvdb::tools::BoxSampler::sample(*mEmission, p))) * emissionColor(mEmissionColor, p);
    }
    if (mTemperature && inTemperatureCell(*mTemperature, p)) {
        out += mModel->blackbody(double(openvdb::tools::BoxSampler::sample(*mTemperature, p)));
    }
    return out;
}

namespace {

/// Kernels of one emitting grid of @a grid, merged by @a lod where the density's kernels merge
/// and quasi-interpolated as the density's, with every positive value kept (the density's
/// cutoff is a density's).
KernelSet kernelsOf(const GridSource::Impl& emitter, const GridSource::Impl& grid, const RenderSettings& settings,
    const LevelOfDetail* lod, Progress* progress, const MemoryBudget* budget)
{
    RenderSettings all = settings;
    all.cutoff = double(std::numeric_limits<float>::min());
    const LevelSource density{&grid.field->tree(), float(settings.cutoff)};
    KernelSet set = extractKernels(emitter, all, lod, progress, budget, &density);
    if (settings.splat.prefilter) quasiInterpolate(emitter, quasiInterpolationAlpha(settings.splat.kernelSigma), set);
    return set;
}

void append(EmitterKernels& out, const KernelSet& set, const std::vector<Rgb>& radiance)
{
    out.kernels.kernels.insert(out.kernels.kernels.end(), set.kernels.begin(), set.kernels.end());
    out.radiance.insert(out.radiance.end(), radiance.begin(), radiance.end());
    out.kernels.activeVoxels += set.activeVoxels;
    out.kernels.activeTiles += set.activeTiles;
    out.kernels.notANumber += set.notANumber;
    out.kernels.clamped += set.clamped;
}

/// A temperature grid classified per voxel (BlackbodyVoxels): each voxel's mean blackbody
/// luminance over its cube and the colour of that light (luminance-weighted, so of luminance 1).
struct BlackbodyVoxels
{
    openvdb::FloatGrid::Ptr luminance;
    openvdb::Vec3SGrid::Ptr colour;
};

/// Samples a side per voxel for its mean blackbody: the midpoint rule on T^4 of the trilinear
/// temperature, within 0.2 % of the exact mean across a face where it falls to 0 K.
constexpr int kBlackbodySamples = 4;

/// The blackbody of the trilinear temperature averaged over every voxel it reaches (the
/// temperature's voxels and the one-voxel shell its interpolation spreads into), so that the
/// kernels carry the light a renderer sampling T along rays would see (docs/equations.md#
/// emission-grids), not T^4 of the voxel value, which over-lights every edge. Voxels whose
/// 27-neighbourhood is active and uniform take their value directly. @a progress: one unit per leaf.
BlackbodyVoxels classifyBlackbody(const GridSource::Impl& temperature, const EmissionModel& model, Progress* progress,
    const MemoryBudget* budget)
{
    // A float and a Vec3s a voxel, the shell at most doubling a sparse grid's voxels.
    if (budget) {
        budget->check(2.0 * (double(temperature.activeVoxels) + 512.0 * double(temperature.activeTiles)), "temperature voxels classified", 16.0);
    }
    BlackbodyVoxels out;
    out.luminance = openvdb::FloatGrid::create(0.0f);
    out.luminance->setTransform(temperature.field->transform().copy());
    out.luminance->tree().topologyUnion(temperature.field->tree());
    out.luminance->tree().voxelizeActiveTiles();
    openvdb::tools::dilateActiveValues(out.luminance->tree(), 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
    out.colour = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    out.colour->setTransform(temperature.field->transform().copy());
    out.colour->tree().topologyUnion(out.luminance->tree());
    std::vector<openvdb::FloatTree::LeafNodeType*> leaves;
    out.luminance->tree().getNodes(leaves);
    setUnits(progress, leaves.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        auto t = temperature.field->getConstAccessor();
        auto colour = out.colour->getAccessor();
        for (std::size_t l = r.begin(); l < r.end(); ++l) {
            for (auto it = leaves[l]->beginValueOn(); it; ++it) {
                const openvdb::Coord ijk = it.getCoord();
                const float centre = t.getValue(ijk);
                bool uniform = true;
                for (int dz = -1; dz <= 1 && uniform; ++dz)
                    for (int dy = -1; dy <= 1 && uniform; ++dy)
                        for (int dx = -1; dx <= 1 && uniform; ++dx) {
                            float v = 0.0f;
                            uniform = t.probeValue(ijk.offsetBy(dx, dy, dz), v) && v == centre;
                        }
                double y = 0.0;
                Vec3d rgb(0.0);
                if (uniform) {
                    y = model.blackbodyLuminance(double(centre));
                    rgb = y * model.blackbodyColour(double(centre));
                } else {
                    constexpr int n = kBlackbodySamples;
                    for (int k = 0; k < n; ++k)
                        for (int j = 0; j < n; ++j)
                            for (int i = 0; i < n; ++i) {
                                const openvdb::Vec3d p = ijk.asVec3d() + (openvdb::Vec3d(i, j, k) + 0.5) / double(n) - 0.5;
                                if (!inTemperatureCell(t, p)) continue; // as EmissionSampler
                                const double value = double(openvdb::tools::BoxSampler::sample(t, p));
                                const double sampleY = model.blackbodyLuminance(value);
                                if (!(sampleY > 0.0)) continue;
                                y += sampleY;
                                rgb += sampleY * model.blackbodyColour(value);
                            }
                    y /= double(n * n * n);
                    rgb /= double(n * n * n);
                }
                it.setValue(float(y));
                const Vec3d c = y > 0.0 ? rgb / y : Vec3d(0.0);
                colour.setValue(ijk, openvdb::Vec3s(float(c.x), float(c.y), float(c.z)));
            }
            advance(progress);
        }
    });
    return out;
}

/// A light sampled at index-space points: its weight (per unit colour) and its colour there.
struct LightSample
{
    double weight = 0.0;
    Rgb colour{0.0f, 0.0f, 0.0f};
};

/// Replace the unit kernels of @a set (and their @a radiance) at the voxels of @a sampled by
/// the light's samples on its fine lattice, the points c + a / n (a = 0 .. n - 1 a side) of every
/// cell c of @a cells (cellsAround @a sampled), the lattice refineKernels uses. A sample carries the sampled
/// voxels' share of the trilinear partition of unity at its point (1 inside, falling across the
/// cells where sampled voxels meet kept ones), so that it and the kept voxels' kernels add up to
/// the light once (docs/lighting.md#emission-at-dense-hot-edges-and-refined-emitters). Its weight
/// is prefiltered with the fine lattice's Laplacian (quasi_interpolation.h); it keeps its point's
/// colour. @a makeLight() gives a thread's sampler, p -> LightSample. Deterministic: the kernels
/// kept in their order, then the samples in the cells' tree order. @a progress: one unit a leaf
/// node of cells, throws Cancelled.
template <typename MakeLight>
void refineEmitters(KernelSet& set, std::vector<Rgb>& radiance, const openvdb::MaskGrid& sampled, const openvdb::MaskGrid& cells, int n,
    double alpha, Progress* progress, MakeLight&& makeLight)
{
    if (n <= 1 || sampled.tree().empty()) return;
    const int m = n + 2;
    using MaskLeaf = openvdb::MaskTree::LeafNodeType;
    std::vector<const MaskLeaf*> leaves;
    cells.tree().getNodes(leaves);
    std::vector<std::vector<Kernel>> kernels(leaves.size());
    std::vector<std::vector<Rgb>> colours(leaves.size());
    setUnits(progress, leaves.size());
    const FineTents tent(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        auto light = makeLight();
        auto inSampled = sampled.getConstAccessor();
        std::vector<LightSample> f(std::size_t(m * m * m));
        const auto at = [&](int i, int j, int k) -> LightSample& { return f[std::size_t((i * m + j) * m + k)]; };
        for (std::size_t l = r.begin(); l < r.end(); ++l) {
            for (auto it = leaves[l]->cbeginValueOn(); it; ++it) {
                const openvdb::Coord cell = it.getCoord();
                // The sampled share of the partition of unity at the fine points of the cell and
                // one beyond each side, from the tents of the cell's 4^3 voxels (separably).
                double share[kMaxFine][kMaxFine][kMaxFine];
                shareOf(inSampled, cell, tent, share);
                bool any = false;
                for (int i = 0; i < m; ++i)
                    for (int j = 0; j < m; ++j)
                        for (int k = 0; k < m; ++k) {
                            LightSample& s = at(i, j, k);
                            s = share[i][j][k] > 0.0 ? light(cell.asVec3d() + openvdb::Vec3d(i - 1, j - 1, k - 1) / double(n)) : LightSample{};
                            s.weight *= share[i][j][k];
                            any = any || s.weight > 0.0;
                        }
                if (!any) continue;
                prefilterFineSamples(n, alpha, [&](int i, int j, int k) { return at(i, j, k).weight; }, [&](int i, int j, int k, float w) {
                    const Vec3d p = Vec3d(cell.x(), cell.y(), cell.z()) + Vec3d(i - 1, j - 1, k - 1) / double(n);
                    kernels[l].push_back({p, w, float(1.0 / n)});
                    colours[l].push_back(at(i, j, k).colour);
                });
            }
        }
        advance(progress, r.size());
    });
    // The kernels that stay, then the samples.
    auto inSampled = sampled.getConstAccessor();
    std::size_t kept = 0;
    for (std::size_t i = 0; i < set.kernels.size(); ++i) {
        const Kernel& k = set.kernels[i];
        if (isUnitKernel(k) && inSampled.isValueOn(voxelOf(k))) continue;
        set.kernels[kept] = k;
        radiance[kept] = radiance[i];
        ++kept;
    }
    set.kernels.resize(kept);
    radiance.resize(kept);
    for (std::size_t l = 0; l < leaves.size(); ++l) {
        set.kernels.insert(set.kernels.end(), kernels[l].begin(), kernels[l].end());
        radiance.insert(radiance.end(), colours[l].begin(), colours[l].end());
    }
}

/// Where one kernel a voxel cannot carry an emitter's light (docs/lighting.md#emission-at-dense-
/// hot-edges-and-refined-emitters): the light does not go as the density, its source function
/// (light over density, a voxel's values) changing several-fold from one voxel to the next (the
/// 3^3 neighbourhood's spread over its largest, kSteepSource or more; light with no density
/// beside light with density counts), where the density is optically thick (kappa x its largest
/// value there, kThickVoxel or more a voxel). There a voxel's Gaussian spreads its light half a
/// voxel from where the density lets it out; where the light goes as the density, their
/// kernels keep the same shapes and the source function is right.
constexpr double kSteepSource = 0.75;
constexpr double kThickVoxel = 0.5;

/// The voxels whose emitter kernels refineEmitters replaces, by lattice: the voxels of @a light
/// (per-voxel light) whose source function is steep where the density is thick, with their 26
/// neighbours (where the light falls to 0 beyond the grid's voxels), on lattices up to
/// --refine-emission; and the density's refined voxels (@a refined), on lattices up to the
/// finer of --refine and --refine-emission.
/// Each voxel on the finest lattice its leaf node's voxels span in pixels (spacing 1/n, n pixels
/// or more a voxel, as refineKernels; so coarser views still refine at n = 2), none in nodes the
/// level of detail merges or under the light's active tiles (their kernels stay). Lattices meet
/// through the partition of unity (refineEmitters); a voxel on two stays on the finer. The
/// finest n is lowered until the samples fit @a within kernels; @a lowered says so. @a progress:
/// checked for a cancel.
struct EmitterLattices
{
    struct Lattice
    {
        int n;                                 ///< >= 2
        openvdb::MaskGrid::Ptr voxels, cells; ///< its voxels and the cells around them (cellsAround)
    };
    std::vector<Lattice> lattices;
    double samples = 0.0; ///< kernels they will make, at most
    bool lowered = false;
};
EmitterLattices emitterLattices(const openvdb::FloatGrid& light, const GridSource::Impl& grid, const RenderSettings& settings,
    const LevelOfDetail* lod, const EmitterRefinement& refined, double within, Progress* progress)
{
    EmitterLattices out;
    if (!lod) return out; // no screen sizes: nothing is refined
    const Vec3d extinction = settings.medium.extinction();
    const double kappa = std::max({extinction.x, extinction.y, extinction.z});
    const int steepFinest = std::min(settings.splat.refineEmission, kMaxRefinement);
    const int sampledFinest = std::min(std::max(refined.n, settings.splat.refineEmission), kMaxRefinement);
    const float cutoff = float(settings.cutoff);
    // The finest lattice a voxel's node allows (1: none); voxels come in tree order, so the
    // last node's answer is kept.
    auto lightAcc = light.getConstAccessor();
    openvdb::Coord lastNode(std::numeric_limits<int>::max());
    int lastLattice = 1;
    const auto nodeLattice = [&](const openvdb::Coord& ijk) {
        const openvdb::Coord origin(ijk.x() & ~7, ijk.y() & ~7, ijk.z() & ~7);
        if (origin != lastNode) {
            lastNode = origin;
            lastLattice = lod->nodeLevels(origin, 8).merges() ? 1
                          : int(std::clamp(std::floor(lod->voxelPixels(origin, 8)), 1.0, double(kMaxRefinement)));
        }
        return lastLattice;
    };
    // The steep, thick voxels.
    auto steep = openvdb::MaskGrid::create(false);
    if (steepFinest > 1) {
        using LeafType = openvdb::FloatTree::LeafNodeType;
        std::vector<const LeafType*> leaves;
        light.tree().getNodes(leaves);
        std::vector<std::uint8_t> flags(leaves.size() * LeafType::SIZE, 0);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()), [&](const tbb::blocked_range<std::size_t>& r) {
            if (progress) progress->check();
            auto value = light.getConstAccessor();
            auto rho = grid.field->getConstAccessor();
            for (std::size_t l = r.begin(); l < r.end(); ++l) {
                for (auto it = leaves[l]->cbeginValueOn(); it; ++it) {
                    const openvdb::Coord ijk = it.getCoord();
                    // The source function, light over density, of the neighbourhood's voxels
                    // that have either (infinite: light with no density).
                    constexpr double kInf = std::numeric_limits<double>::infinity();
                    double lo = kInf, hi = 0.0, dense = 0.0;
                    for (int x = -1; x <= 1; ++x)
                        for (int y = -1; y <= 1; ++y)
                            for (int z = -1; z <= 1; ++z) {
                                const openvdb::Coord c = ijk.offsetBy(x, y, z);
                                const double v = std::max(double(value.getValue(c)), 0.0);
                                const float r = rho.getValue(c);
                                const double d = r >= cutoff ? double(r) : 0.0;
                                if (!(v > 0.0) && !(d > 0.0)) continue;
                                const double source = d > 0.0 ? v / d : kInf;
                                lo = std::min(lo, source);
                                hi = std::max(hi, source);
                                dense = std::max(dense, d);
                            }
                    const bool steepSource = lo < kInf && (hi == kInf || hi - lo >= kSteepSource * hi) && hi > 0.0;
                    if (steepSource && kappa * dense >= kThickVoxel) flags[l * LeafType::SIZE + it.pos()] = 1;
                }
            }
        });
        auto acc = steep->getAccessor();
        for (std::size_t l = 0; l < leaves.size(); ++l)
            for (auto it = leaves[l]->cbeginValueOn(); it; ++it) {
                if (flags[l * LeafType::SIZE + it.pos()]) acc.setValueOn(it.getCoord());
            }
        openvdb::tools::dilateActiveValues(steep->tree(), 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
    }
    for (int finest = sampledFinest; finest > 1; --finest) {
        if (progress) progress->check();
        std::vector<openvdb::MaskGrid::Ptr> masks(std::size_t(finest + 1));
        const auto add = [&](const openvdb::MaskGrid& voxels, int cap) {
            for (auto it = voxels.cbeginValueOn(); it; ++it) {
                const openvdb::Coord ijk = it.getCoord();
                const int n = std::min({nodeLattice(ijk), finest, cap});
                if (n < 2 || (lightAcc.isValueOn(ijk) && !lightAcc.probeConstLeaf(ijk))) continue; // an active tile's kernels stay
                if (!masks[std::size_t(n)]) masks[std::size_t(n)] = openvdb::MaskGrid::create(false);
                masks[std::size_t(n)]->tree().setValueOn(ijk);
            }
        };
        add(*steep, steepFinest);
        if (refined.sampled) add(*refined.sampled, sampledFinest);
        double samples = 0.0;
        std::vector<EmitterLattices::Lattice> lattices;
        for (int n = finest; n >= 2; --n) {
            const openvdb::MaskGrid::Ptr& voxels = masks[std::size_t(n)];
            if (!voxels) continue;
            for (int finer = n + 1; finer <= finest; ++finer) {
                if (masks[std::size_t(finer)]) voxels->tree().topologyDifference(masks[std::size_t(finer)]->tree());
            }
            if (voxels->tree().empty()) continue;
            lattices.push_back({n, voxels, cellsAround(*voxels)});
            samples += double(lattices.back().cells->activeVoxelCount()) * n * n * n;
        }
        if (samples <= within) {
            out.lattices = std::move(lattices);
            out.samples = samples;
            return out;
        }
        out.lowered = true;
    }
    return out;
}

} // namespace

EmitterKernels emitterKernels(const GridSource::Impl& grid, const RenderSettings& settings, const LevelOfDetail* lod, Progress* progress,
    const MemoryBudget* budget, const EmitterRefinement& refined)
{
    EmitterKernels out;
    if (!grid.emission && !grid.temperature) return out; // and no blackbody table to build
    const EmissionModel model(settings);
    const double alpha = settings.splat.prefilter ? quasiInterpolationAlpha(settings.splat.kernelSigma) : 0.0;
    // Refined emitter kernels of both grids take at most a quarter of the budget, and no more
    // than the kernels already held leave (the renderer's check of them all).
    double within = std::min(kRefinedKernelBudget, budget ? budget->itemsWithin(0.25, kBytesPerKernel) : kRefinedKernelBudget);
    if (budget) within = std::min(within, budget->itemsWithin(1.0, kBytesPerKernel) - double(refined.kernelsHeld));
    // Refine one grid's kernels where its per-voxel @a light asks for it, within what is left.
    const auto refine = [&](KernelSet& set, std::vector<Rgb>& radiance, const openvdb::FloatGrid& light, const auto& makeLight) {
        within -= double(set.kernels.size());
        const EmitterLattices lattices = emitterLattices(light, grid, settings, lod, refined, within, progress);
        within -= lattices.samples;
        out.refinementLowered = out.refinementLowered || lattices.lowered;
        for (const EmitterLattices::Lattice& lattice : lattices.lattices) {
            refineEmitters(set, radiance, *lattice.voxels, *lattice.cells, lattice.n, alpha, progress, makeLight);
        }
    };
    if (grid.emission) {
        KernelSet set = kernelsOf(*grid.emission, grid, settings, lod, progress, budget);
        const Vec3d c = model.emitted(1.0);
        const Rgb colour{float(c.x), float(c.y), float(c.z)};
        // Times the colour per voxel where there is one (a mixed frame's), at each kernel.
        const auto coloured = [c](std::optional<openvdb::Vec3SGrid::ConstAccessor>& acc, const openvdb::Vec3d& p) {
            const Vec3d e = c * emissionColor(acc, p);
            return Rgb{float(e.x), float(e.y), float(e.z)};
        };
        std::vector<Rgb> radiance(set.kernels.size(), colour);
        if (grid.emissionColor) {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, radiance.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
                std::optional<openvdb::Vec3SGrid::ConstAccessor> acc(grid.emissionColor->getConstAccessor());
                for (std::size_t i = r.begin(); i < r.end(); ++i) {
                    const Vec3d& p = set.kernels[i].pIndex;
                    radiance[i] = coloured(acc, openvdb::Vec3d(p.x, p.y, p.z));
                }
            });
        }
        refine(set, radiance, *grid.emission->field, [&] {
            std::optional<openvdb::Vec3SGrid::ConstAccessor> chroma;
            if (grid.emissionColor) chroma.emplace(grid.emissionColor->getConstAccessor());
            return [acc = grid.emission->field->getConstAccessor(), chroma, coloured](const openvdb::Vec3d& p) mutable {
                return LightSample{std::max(double(openvdb::tools::BoxSampler::sample(acc, p)), 0.0), coloured(chroma, p)};
            };
        });
        append(out, set, radiance);
    }
    if (grid.temperature) {
        for (auto it = grid.temperature->field->cbeginValueOn(); it; ++it) {
            out.hottestKelvin = std::fmax(out.hottestKelvin, model.kelvin(double(*it))); // fmax passes NaN by
        }
        const BlackbodyVoxels voxels = classifyBlackbody(*grid.temperature, model, progress, budget);
        auto source = std::make_shared<GridSource::Impl>(*grid.temperature);
        source->grid = voxels.luminance;
        source->derive();
        KernelSet set = kernelsOf(*source, grid, settings, lod, progress, budget);
        // Each kernel's colour: its voxel's (trilinear at other lattice points: halo kernels).
        std::vector<Rgb> radiance(set.kernels.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, radiance.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
            auto colour = voxels.colour->getConstAccessor();
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                const Vec3d& p = set.kernels[i].pIndex;
                const openvdb::Vec3s c = openvdb::tools::BoxSampler::sample(colour, openvdb::Vec3d(p.x, p.y, p.z));
                radiance[i] = Rgb{c.x(), c.y(), c.z()};
            }
        });
        refine(set, radiance, *voxels.luminance, [&] {
            return [acc = grid.temperature->field->getConstAccessor(), &model](const openvdb::Vec3d& p) mutable {
                if (!inTemperatureCell(acc, p)) return LightSample{};
                const double value = double(openvdb::tools::BoxSampler::sample(acc, p));
                const Vec3d c = model.blackbodyColour(value);
                return LightSample{model.blackbodyLuminance(value), Rgb{float(c.x), float(c.y), float(c.z)}};
            };
        });
        append(out, set, radiance);
    }
    return out;
}

} // namespace detail
} // namespace vdb_ewa
