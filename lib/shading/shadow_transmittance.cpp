/// @file shadow_transmittance.cpp
#include "shading/shadow_transmittance.h"

#include "source/source.h"
#include "support/empty_space.h"
#include "support/openvdb_tools.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vdb_ewa {
namespace detail {

ShadowMarcher::ShadowMarcher(const GridSource::Impl& grid, const RenderSettings& settings, std::size_t light)
    : mGrid(grid), mSkipper(*grid.field, 0), mSettings(settings), mModel(settings)
{
    const Vec3d l = settings.lights[light].unitDirection();
    mLightWorld = l;
    if (grid.linear) {
        // Index-space displacement per voxel length travelled towards the light.
        mStepIndex = glm::inverse(grid.indexToWorldLinear) * l * grid.voxelLength;
    }
    const openvdb::CoordBBox box = grid.field->evalActiveVoxelBoundingBox();
    mBoxMin = Vec3d(box.min().x(), box.min().y(), box.min().z()) - 1.0;
    mBoxMax = Vec3d(box.max().x(), box.max().y(), box.max().z()) + 1.0;
}

Rgb ShadowMarcher::march(const Vec3d& pIndex)
{
    const double step = mSettings.shadow.step;
    const double cutoff = mSettings.cutoff;
    const double gain = mSettings.shadow.gain;
    double t[3] = {1.0, 1.0, 1.0};
    // Voxel lengths until the ray leaves the padded active bounding box.
    const double sMax = exitDistance(pIndex);
    double s = step;
    while (s <= sMax) {
        const Vec3d p = indexAt(pIndex, s);
        // Skip empty nodes: jump to the first sample past the node's safe interior.
        const double jump = mGrid.linear ? mSkipper.emptyExit(p, mStepIndex) : 0.0;
        const double skipTo = s + jump;
        if (jump > 0.0) {
            s = step * std::ceil(skipTo / step);
            if (s == skipTo) s += step;
            continue;
        }
        float d = 0.0f;
        openvdb::tools::BoxSampler::sample(mSkipper.accessor(), openvdb::Vec3d(p.x, p.y, p.z), d);
        if (d >= cutoff) {
            const double length = step / (1.0 + s * gain); // vdb_render's in-scattering gain
            for (int c = 0; c < 3; ++c) t[c] *= std::exp(-mModel.opticalDepth(c, d, length));
            if (t[0] * t[0] + t[1] * t[1] + t[2] * t[2] < cutoff) break;
        }
        s += step;
    }
    return Rgb{float(t[0]), float(t[1]), float(t[2])};
}

Vec3d ShadowMarcher::indexAt(const Vec3d& start, double s) const
{
    if (mGrid.linear) return start + s * mStepIndex;
    const auto& xform = mGrid.grid->transform();
    const openvdb::Vec3d w0 = xform.indexToWorld(openvdb::Vec3d(start.x, start.y, start.z));
    const Vec3d w = Vec3d(w0.x(), w0.y(), w0.z()) + s * mGrid.voxelLength * mLightWorld;
    const openvdb::Vec3d i = xform.worldToIndex(openvdb::Vec3d(w.x, w.y, w.z));
    return {i.x(), i.y(), i.z()};
}

double ShadowMarcher::exitDistance(const Vec3d& start) const
{
    if (!mGrid.linear) {
        // No closed form through a frustum map: bound by the box diagonal in world units.
        const Vec3d diag = mBoxMax - mBoxMin;
        return glm::length(mGrid.indexToWorldLinear * diag) / mGrid.voxelLength * 2.0 + 1.0;
    }
    return boxExit(start, mStepIndex, mBoxMin, mBoxMax + 1.0);
}

namespace {

/// March from every point of a list towards every light ([point * lights + light]; 1 for a
/// dark light), one task per block.
std::vector<Rgb> marchAll(const GridSource::Impl& grid, const std::vector<Vec3d>& points, const RenderSettings& settings,
    Progress* progress)
{
    const std::size_t lights = settings.lights.size();
    const OpticalModel model(settings);
    std::vector<Rgb> out(points.size() * lights, Rgb{1.0f, 1.0f, 1.0f});
    setUnits(progress, points.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024),
        [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t l = 0; l < lights; ++l) {
                if (model.dark(l)) continue;
                ShadowMarcher marcher(grid, settings, l);
                for (std::size_t i = range.begin(); i < range.end(); ++i) out[i * lights + l] = marcher.march(points[i]);
            }
            advance(progress, range.size());
        });
    return out;
}

} // namespace

std::vector<Rgb> shadowTransmittance(const GridSource::Impl& grid, const KernelSet& kernels,
    const RenderSettings& settings, Progress* progress)
{
    // No scattering or no light: nothing is lit, so the transmittance is never used.
    if (OpticalModel(settings).unlit()) {
        return std::vector<Rgb>(kernels.kernels.size() * settings.lights.size(), Rgb{1.0f, 1.0f, 1.0f});
    }
    std::vector<Vec3d> centres(kernels.kernels.size());
    for (std::size_t i = 0; i < centres.size(); ++i) centres[i] = kernels.kernels[i].pIndex;
    return marchAll(grid, centres, settings, progress);
}

} // namespace detail
} // namespace vdb_ewa
