/// @file shadow_transmittance.h
/// @brief Transmittance from each kernel centre towards the directional light (pre-shading:
///        one colour per kernel, as the paper's c_k). The model is vdb_render's shadow ray.
#pragma once

#include "kernel_extraction.h"

#include <array>
#include <vector>

namespace vdb_ewa {
namespace detail {

using Rgb = std::array<float, 3>;

/// March from each kernel centre towards the light: samples at s = k * shadowStep voxel
/// lengths (k >= 1), trilinear density d, T *= exp(-sigma_t d shadowStep / (1 + gain s)),
/// stop where |T|^2 < cutoff; empty tree nodes are skipped. One task per block of kernels.
/// @a progress: one unit per march; throws Cancelled.
std::vector<Rgb> shadowTransmittance(const GridSource::Impl& grid, const KernelSet& kernels,
    const RenderSettings& settings, Progress* progress = nullptr);

/// The same march for one world-space point (used by tests and reference integrators).
Rgb shadowTransmittanceAt(const GridSource::Impl& grid, const Vec3d& pIndex, const RenderSettings& settings);

} // namespace detail
} // namespace vdb_ewa
