/// @file reference_integrator.h
/// @brief The reference integrators, yardsticks for accuracy, not for speed:
///        `--method raymarch` integrates *the field* a VDB grid stands for (the trilinear
///        interpolation of its voxel values, what vdb_render and production volume renderers
///        converge to) with a shadow ray per sample; `--method raymarch-gaussian` integrates the
///        splatter's own Gaussian reconstruction with its per-kernel shadows, to measure
///        splatting's approximations apart from the reconstruction's.
#pragma once

#include "source/source.h"
#include "support/memory_budget.h"
#include "support/progress.h"

#include <vdb_ewa/camera.h>
#include <vdb_ewa/frame.h>
#include <vdb_ewa/render_stats.h>

namespace vdb_ewa {
namespace detail {

/// Kernels are truncated at this many standard deviations per axis (mass lost < 1e-4).
constexpr double kReferenceTruncation = 4.0;

/// March every pixel's centre ray in steps of settings.step voxel lengths through the field
/// (GridSource::Impl::field, trilinear), sampling at step midpoints: density (samples below
/// --cutoff skipped, as vdb_render does), the light's transmittance from a ShadowMarcher
/// started at the sample, the material colour there; each step is composited with the exact
/// homogeneous update (OpticalModel). Passes: Z (the crossing found within a step as in the
/// splatter) and transmittance. Motion blur: each ray at its own shutter time samples the still
/// field where the material there came from (MovedVoxels; @a budget bounds them). @throw
/// ValueError for non-affine grids and for the other passes, BudgetError. @a progress: one unit
/// per row; throws Cancelled.
Frame rayMarchReference(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings,
    const PassRequest& passes, const MemoryBudget& budget, RenderStats& stats, Progress* progress = nullptr);

/// The same march through the splatter's Gaussian reconstruction instead: the sum of all
/// kernels within 4 sigma (active tiles voxelised: unit-spaced kernels), each pre-shaded with
/// the shadow transmittance at its centre as the splatter does. @a progress: 0-15 % kernels
/// and shadows, 15-100 % one unit per row.
Frame rayMarchGaussianSum(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings,
    const PassRequest& passes, RenderStats& stats, Progress* progress = nullptr);

} // namespace detail
} // namespace vdb_ewa
