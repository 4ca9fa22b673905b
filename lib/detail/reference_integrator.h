/// @file reference_integrator.h
/// @brief `--method raymarch`: a ray marcher through the *same* Gaussian reconstruction the
///        splatter uses (sum of all kernels, exact exponentials, the same optical model and
///        shadow transmittance). A yardstick for the splatter's approximations, not for speed.
#pragma once

#include "kernel_extraction.h"
#include "progress.h"

#include <vdb_ewa/camera.h>
#include <vdb_ewa/frame.h>
#include <vdb_ewa/renderer.h>

namespace vdb_ewa {
namespace detail {

/// Kernels are truncated at this many standard deviations per axis (mass lost < 1e-4).
constexpr double kReferenceTruncation = 4.0;

/// March every pixel's centre ray in steps of settings.step voxel lengths, sampling
/// extinction and emission at step midpoints from all kernels within 4 sigma, and composite
/// each step with the exact homogeneous update. Active tiles are voxelised (their kernels are
/// unit-spaced here). Passes: Z (the crossing found within a step as in the splatter) and
/// transmittance. @throw ValueError for non-affine grids and for the other passes.
/// @a progress: 0-15 % kernels and shadows, 15-100 % one unit per row; throws Cancelled.
Frame rayMarchReference(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings,
    const PassRequest& passes, RenderStats& stats, Progress* progress = nullptr);

} // namespace detail
} // namespace vdb_ewa
