/// @file shadow_transmittance.h
/// @brief Transmittance from each kernel centre towards each directional light (pre-shading:
///        one colour per kernel, as the paper's c_k). The model is vdb_render's shadow ray.
#pragma once

#include "shading/optical_model.h"
#include "source/source.h"
#include "support/empty_space.h"
#include "support/rgb.h"

#include <array>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// vdb_render's shadow ray through the field (GridSource::Impl::field) towards directional
/// light settings.lights[light], for one thread (it owns a ValueAccessor): samples at s = k * shadow.step voxel
/// lengths (k >= 1), trilinear density d, T *= exp(-sigma_t d shadow.step / (1 + shadow.gain s)),
/// stopping where |T|^2 < cutoff; empty tree nodes are skipped.
class ShadowMarcher
{
public:
    ShadowMarcher(const GridSource::Impl& grid, const RenderSettings& settings, std::size_t light);

    /// The light's transmittance at the index-space point @a pIndex.
    Rgb march(const Vec3d& pIndex);

private:
    Vec3d indexAt(const Vec3d& start, double s) const;
    /// Distance (voxel lengths) at which the ray leaves the padded active bounding box.
    double exitDistance(const Vec3d& start) const;

    const GridSource::Impl& mGrid;
    EmptySpaceSkipper mSkipper;
    const RenderSettings& mSettings;
    OpticalModel mModel;
    Vec3d mLightWorld;
    Vec3d mStepIndex{0.0};
    Vec3d mBoxMin, mBoxMax;
};

/// ShadowMarcher from each kernel centre (the shading of --method raymarch-gaussian, which
/// models per-kernel pre-shading), for every light: [kernel * lights + light]. One task per
/// block of kernels. @a progress: one unit per march; throws Cancelled.
std::vector<Rgb> shadowTransmittance(const GridSource::Impl& grid, const KernelSet& kernels,
    const RenderSettings& settings, Progress* progress = nullptr);

} // namespace detail
} // namespace vdb_ewa
