/// @file quasi_interpolation.h
/// @brief Kernel weights that make the Gaussian sum reproduce the trilinear field: a
///        quasi-interpolating prefilter (docs/numerics.md#quasi-interpolation).
///
/// The sum of unit-spaced Gaussians of standard deviation sigma over voxel values v has the
/// spectrum V(f) exp(-2 pi^2 sigma^2 f^2) per axis; the trilinear field (OpenVDB's BoxSampler,
/// what vdb_render converges to) has V(f) sinc^2(f) = V(f) (1 - pi^2 f^2 / 3 + ...). Weights
/// c = v + alpha sum_axes (2 v_n - v_(n-1) - v_(n+1)), alpha = sigma^2 / 2 - 1 / 12, match the
/// two to second order in f: the Gaussian sum then has the trilinear field's local second
/// moment, so a kernel wide enough for a flat partition of unity (sigma 0.55: 1.5 % ripple)
/// is no blurrier than the trilinear field. Voxels next to the kernels' support get kernels of
/// negative weight -alpha sum v_neighbours (a halo), which cancel the Gaussians' spill beyond
/// the field's support at the faces of dense media (Maz'ya and Schmidt, "Approximate
/// Approximations", 2007, Ch. 2; Unser, "Splines: a perfect fit", 1999, on prefiltering).
#pragma once

#include "source/kernel_extraction.h"

namespace vdb_ewa {
namespace detail {

/// The prefilter's alpha for kernels of standard deviation @a sigma voxels: sigma^2 / 2 - 1/12,
/// 0 where the Gaussian is already as sharp as the trilinear hat (sigma^2 <= 1/6).
double quasiInterpolationAlpha(double sigma);

/// Reweight the unit-spaced kernels of @a set (voxels and spacing-1 tile kernels) by the
/// prefilter with @a alpha, reading neighbour values from @a grid's field, and append one
/// halo kernel for each inactive face neighbour of theirs (in a deterministic order). Kernels
/// on coarser lattices are left as they are; voxels in @a sampled (refineKernels) get no halo
/// kernel. Returns the number of halo kernels added.
/// @a units: where given, the unit kernels that own halos are the whole grid's (a window of
/// bricks of the streamed frame: its halos are the ones the whole grid's kernels would have);
/// null: the set's own.
struct UnitKernelRule
{
    const RenderSettings& settings;
    const LevelOfDetail* lod;
};
std::uint64_t quasiInterpolate(const GridSource::Impl& grid, double alpha, KernelSet& set,
    const openvdb::MaskGrid* sampled = nullptr, const UnitKernelRule* units = nullptr);

} // namespace detail
} // namespace vdb_ewa
