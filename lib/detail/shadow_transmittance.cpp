/// @file shadow_transmittance.cpp
#include "shadow_transmittance.h"

#include "empty_space.h"
#include "grid_source_impl.h"
#include "openvdb_tools.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vdb_ewa {
namespace detail {
namespace {

/// Shadow-ray marcher for one thread (owns a ValueAccessor, S7).
class ShadowMarcher
{
public:
    ShadowMarcher(const GridSource::Impl& grid, const RenderSettings& settings)
        : mGrid(grid), mSkipper(*grid.grid, 0), mSettings(settings)
    {
        const Vec3d l = glm::normalize(settings.lightDir);
        mLightWorld = l;
        if (grid.linear) {
            // Index-space displacement per voxel length travelled towards the light.
            mStepIndex = glm::inverse(grid.indexToWorldLinear) * l * grid.voxelLength;
        }
        const openvdb::CoordBBox box = grid.grid->evalActiveVoxelBoundingBox();
        mBoxMin = Vec3d(box.min().x(), box.min().y(), box.min().z()) - 1.0;
        mBoxMax = Vec3d(box.max().x(), box.max().y(), box.max().z()) + 1.0;
        for (int c = 0; c < 3; ++c) mExtinction[c] = settings.absorb[c] + settings.scatter[c];
    }

    Rgb march(const Vec3d& pIndex)
    {
        Rgb trans{1.0f, 1.0f, 1.0f};
        const double step = mSettings.shadowStep;
        const double cutoff = mSettings.cutoff;
        const double gain = mSettings.gain;
        double t[3] = {1.0, 1.0, 1.0};
        // Voxel lengths until the ray leaves the padded active bounding box.
        const double sMax = exitDistance(pIndex);
        double s = step;
        while (s <= sMax) {
            const Vec3d p = indexAt(pIndex, s);
            const openvdb::Vec3d pv(p.x, p.y, p.z);
            // Skip empty nodes: jump to the first sample past the node's safe interior.
            const double jump = mGrid.linear ? mSkipper.emptyExit(p, mStepIndex) : 0.0;
            const double skipTo = s + jump;
            if (jump > 0.0) {
                s = step * std::ceil(skipTo / step);
                if (s == skipTo) s += step;
                continue;
            }
            float d = 0.0f;
            openvdb::tools::BoxSampler::sample(mSkipper.accessor(), pv, d);
            if (d >= cutoff) {
                const double k = d * step / (1.0 + s * gain);
                for (int c = 0; c < 3; ++c) t[c] *= std::exp(-mExtinction[c] * k);
                if (t[0] * t[0] + t[1] * t[1] + t[2] * t[2] < cutoff) break;
            }
            s += step;
        }
        for (int c = 0; c < 3; ++c) trans[c] = float(t[c]);
        return trans;
    }

private:
    Vec3d indexAt(const Vec3d& start, double s) const
    {
        if (mGrid.linear) return start + s * mStepIndex;
        const auto& xform = mGrid.grid->transform();
        const openvdb::Vec3d w0 = xform.indexToWorld(openvdb::Vec3d(start.x, start.y, start.z));
        const Vec3d w = Vec3d(w0.x(), w0.y(), w0.z()) + s * mGrid.voxelLength * mLightWorld;
        const openvdb::Vec3d i = xform.worldToIndex(openvdb::Vec3d(w.x, w.y, w.z));
        return {i.x(), i.y(), i.z()};
    }

    /// Distance (voxel lengths) at which the ray leaves the padded active box.
    double exitDistance(const Vec3d& start) const
    {
        if (!mGrid.linear) {
            // No closed form through a frustum map: bound by the box diagonal in world units.
            const Vec3d diag = mBoxMax - mBoxMin;
            return glm::length(mGrid.indexToWorldLinear * diag) / mGrid.voxelLength * 2.0 + 1.0;
        }
        return boxExit(start, mStepIndex, mBoxMin, mBoxMax + 1.0);
    }

    const GridSource::Impl& mGrid;
    EmptySpaceSkipper mSkipper;
    const RenderSettings& mSettings;
    Vec3d mLightWorld;
    Vec3d mStepIndex{0.0};
    Vec3d mBoxMin, mBoxMax;
    double mExtinction[3];
};

} // namespace

namespace {

/// March from every point of a list, one task per block.
std::vector<Rgb> marchAll(const GridSource::Impl& grid, const std::vector<Vec3d>& points, const RenderSettings& settings,
    Progress* progress)
{
    std::vector<Rgb> out(points.size());
    setUnits(progress, points.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.size(), 1024),
        [&](const tbb::blocked_range<std::size_t>& range) {
            ShadowMarcher marcher(grid, settings);
            for (std::size_t i = range.begin(); i < range.end(); ++i) out[i] = marcher.march(points[i]);
            advance(progress, range.size());
        });
    return out;
}

/// Shadow transmittance on the lattice N Z^3 (index space) around the kernels, trilinearly
/// interpolated at each kernel centre: about N^3 times fewer marches. The lattice points are
/// the corners of the lattice cells that hold a kernel, stored in a sparse grid of point
/// indices (lattice coordinates).
std::vector<Rgb> latticeShadows(const GridSource::Impl& grid, const KernelSet& kernels, const RenderSettings& settings,
    Progress* progress)
{
    const double n = double(settings.shadowResolution);
    openvdb::Int32Grid::Ptr slots = openvdb::Int32Grid::create(-1);
    {
        auto acc = slots->getAccessor();
        for (const Kernel& k : kernels.kernels) {
            const openvdb::Coord base = openvdb::Coord::floor(openvdb::Vec3d(k.pIndex.x, k.pIndex.y, k.pIndex.z) / n);
            for (int c = 0; c < 8; ++c) acc.setValueOn(base.offsetBy(c & 1, (c >> 1) & 1, (c >> 2) & 1), 0);
        }
    }
    std::vector<Vec3d> points;
    points.reserve(slots->activeVoxelCount());
    for (auto it = slots->tree().beginValueOn(); it; ++it) { // tree order: deterministic
        it.setValue(int(points.size()));
        const openvdb::Coord c = it.getCoord();
        points.emplace_back(n * c.x(), n * c.y(), n * c.z());
    }
    const std::vector<Rgb> lattice = marchAll(grid, points, settings, progress);

    std::vector<Rgb> out(kernels.kernels.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.size(), 4096),
        [&](const tbb::blocked_range<std::size_t>& range) {
            auto acc = slots->getConstAccessor();
            for (std::size_t i = range.begin(); i < range.end(); ++i) {
                const Vec3d q = kernels.kernels[i].pIndex / n;
                const openvdb::Coord base = openvdb::Coord::floor(openvdb::Vec3d(q.x, q.y, q.z));
                const Vec3d f = q - Vec3d(base.x(), base.y(), base.z());
                double t[3] = {0.0, 0.0, 0.0};
                for (int c = 0; c < 8; ++c) {
                    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
                    const double w = (dx ? f.x : 1.0 - f.x) * (dy ? f.y : 1.0 - f.y) * (dz ? f.z : 1.0 - f.z);
                    const Rgb& v = lattice[std::size_t(acc.getValue(base.offsetBy(dx, dy, dz)))];
                    for (int ch = 0; ch < 3; ++ch) t[ch] += w * double(v[ch]);
                }
                for (int ch = 0; ch < 3; ++ch) out[i][ch] = float(t[ch]);
            }
        });
    return out;
}

} // namespace

std::vector<Rgb> shadowTransmittance(const GridSource::Impl& grid, const KernelSet& kernels,
    const RenderSettings& settings, Progress* progress)
{
    // No scattering or no light: nothing is lit, so the transmittance is never used.
    const Vec3d lit = settings.scatter * settings.lightColor;
    if (lit.x == 0.0 && lit.y == 0.0 && lit.z == 0.0) {
        return std::vector<Rgb>(kernels.kernels.size(), Rgb{1.0f, 1.0f, 1.0f});
    }
    if (settings.shadowResolution > 1 && grid.linear) return latticeShadows(grid, kernels, settings, progress);
    std::vector<Vec3d> centres(kernels.kernels.size());
    for (std::size_t i = 0; i < centres.size(); ++i) centres[i] = kernels.kernels[i].pIndex;
    return marchAll(grid, centres, settings, progress);
}

Rgb shadowTransmittanceAt(const GridSource::Impl& grid, const Vec3d& pIndex, const RenderSettings& settings)
{
    ShadowMarcher marcher(grid, settings);
    return marcher.march(pIndex);
}

} // namespace detail
} // namespace vdb_ewa
