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

EmissionSampler::EmissionSampler(const GridSource::Impl& grid, const EmissionModel* model) : mModel(model)
{
    if (!model) return;
    if (grid.emission) mEmission.emplace(grid.emission->field->getConstAccessor());
    if (grid.temperature) mTemperature.emplace(grid.temperature->field->getConstAccessor());
}

Vec3d EmissionSampler::at(const Vec3d& pIndex)
{
    const openvdb::Vec3d p(pIndex.x, pIndex.y, pIndex.z);
    Vec3d out(0.0);
    if (mEmission) out += mModel->emitted(double(openvdb::tools::BoxSampler::sample(*mEmission, p)));
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

} // namespace

EmitterKernels emitterKernels(const GridSource::Impl& grid, const RenderSettings& settings, const LevelOfDetail* lod, Progress* progress,
    const MemoryBudget* budget)
{
    EmitterKernels out;
    if (!grid.emission && !grid.temperature) return out; // and no blackbody table to build
    const EmissionModel model(settings);
    if (grid.emission) {
        const KernelSet set = kernelsOf(*grid.emission, grid, settings, lod, progress, budget);
        const Vec3d c = model.emitted(1.0);
        append(out, set, std::vector<Rgb>(set.kernels.size(), Rgb{float(c.x), float(c.y), float(c.z)}));
    }
    if (grid.temperature) {
        for (auto it = grid.temperature->field->cbeginValueOn(); it; ++it) {
            out.hottestKelvin = std::fmax(out.hottestKelvin, model.kelvin(double(*it))); // fmax passes NaN by
        }
        const BlackbodyVoxels voxels = classifyBlackbody(*grid.temperature, model, progress, budget);
        auto source = std::make_shared<GridSource::Impl>(*grid.temperature);
        source->grid = voxels.luminance;
        source->derive();
        const KernelSet set = kernelsOf(*source, grid, settings, lod, progress, budget);
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
        append(out, set, radiance);
    }
    return out;
}

} // namespace detail
} // namespace vdb_ewa
