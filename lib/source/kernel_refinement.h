/// @file kernel_refinement.h
/// @brief Kernels on a lattice finer than the voxels: the trilinear field sampled n times a
///        voxel per axis, one kernel of spacing 1/n per sample (docs/numerics.md#refined-kernels).
///
/// The Gaussian sum of the voxel kernels is not the trilinear field: across a dense face their
/// profiles differ by about the kernel's width (sigma 0.5 voxel), and that difference, not the
/// integration, bounds the splatter's accuracy (docs/numerics.md#dense-faces). Sampling the
/// field itself every 1/n voxel and giving each sample a kernel of standard deviation sigma / n
/// (Eq. 19 with V = (sigma / n)^2 I) shrinks the difference with n, at n^3 the kernels, down to
/// the kernels' own ripple (3.4 % of the field at sigma = 0.5 lattice steps). The samples' weights are quasi-interpolating on the fine lattice
/// (quasi_interpolation.h with the fine lattice's own neighbours), and the one-voxel shell
/// around the kernels' voxels, where the trilinear field is not yet zero, is sampled too (its
/// samples past the field's support are the fine lattice's halo).
#pragma once

#include "source/kernel_extraction.h"

namespace vdb_ewa {
namespace detail {

/// Largest refinement accepted: n^3 kernels a voxel (64 at n = 4).
inline constexpr int kMaxRefinement = 4;

/// Refined kernels cost n^3 a voxel: at most this many (about 10 GB through the pipeline, at
/// kBytesPerKernel), and at most half the memory budget; refined emitters (grid_emission.h) as
/// many again, within a quarter of it.
inline constexpr double kRefinedKernelBudget = 4.0e7;

/// Fine points a side of a cell with one beyond each end, at the finest refinement.
inline constexpr int kMaxFine = kMaxRefinement + 2;

/// The fine lattice's cells that refinement samples around the voxels of @a sampled: every cell
/// (named by its lower corner, holding the points c + a / n, a = 0 .. n - 1 a side) with a
/// corner in @a sampled.
openvdb::MaskGrid::Ptr cellsAround(const openvdb::MaskGrid& sampled);

/// The tent weights, along an axis, of a cell's 4 voxels (-1 .. 2 from its corner) at its n + 2
/// fine points (-1/n .. 1 + 1/n).
struct FineTents
{
    int n, m;
    double weight[kMaxFine][4];
    explicit FineTents(int n_);
};

/// The share of the trilinear partition of unity that the voxels of @a sampled hold at the fine
/// points of @a cell and one beyond each side: 1 where every voxel whose tent reaches a point
/// is sampled, falling to 0 across the cells where sampled voxels meet others. Refined samples
/// carry it so that they and the kernels of the voxels not sampled add up to the field once
/// (docs/numerics.md#refined-kernels).
void shareOf(const openvdb::MaskGrid::ConstAccessor& sampled, const openvdb::Coord& cell, const FineTents& tents,
    double (&share)[kMaxFine][kMaxFine][kMaxFine]);

/// The prefiltered weights of a cell's fine samples (quasi_interpolation.h on the fine lattice:
/// c + @a alpha x (6 c - its 6 neighbours)): @a value(i, j, k) reads the (n + 2)^3 sample values
/// around the cell (index 0 and n + 1: one beyond each side); @a emit(i, j, k, w) receives each
/// of its n^3 samples (i, j, k in 1 .. n) whose weight w is not 0.
template <typename Value, typename Emit>
void prefilterFineSamples(int n, double alpha, Value&& value, Emit&& emit)
{
    for (int i = 1; i <= n; ++i)
        for (int j = 1; j <= n; ++j)
            for (int k = 1; k <= n; ++k) {
                const double c = value(i, j, k);
                const double laplacian = 6.0 * c - value(i - 1, j, k) - value(i + 1, j, k) - value(i, j - 1, k) -
                                         value(i, j + 1, k) - value(i, j, k - 1) - value(i, j, k + 1);
                const float w = float(c + alpha * laplacian);
                if (w != 0.0f) emit(i, j, k, w);
            }
}

/// What refineKernels did.
struct Refinement
{
    int n = 1;                       ///< the lattice used (lowered from the one asked to fit the budget)
    std::uint64_t sampledVoxels = 0; ///< voxels sampled on it
    bool lowered = false;            ///< the budget lowered n
};

/// Replace the unit kernels of @a set (voxels and spacing-1 tile kernels) of the leaf nodes
/// whose voxels span @a n pixels or more (@a scale's voxelPixels), where the field is not
/// uniform around them, by the samples of @a grid's trilinear field every 1/@a n voxel over
/// their voxels and the one-voxel shell around them, each times the sampled voxels' share
/// (shareOf, so that samples and the kernels left add up to the field once), weighted by the
/// prefilter with @a alpha (in fine-lattice units; 0 = the samples' values). Voxels that other
/// kernels model are not sampled: unrefined unit kernels, active voxels with values >= @a cutoff
/// under tiles or merged blocks. @a sampled receives the voxels that were (quasiInterpolate puts
/// no halo kernel there). Where n^3 kernels a cell around them (cellsAround) would exceed
/// @a budget, n is lowered until they fit (n = 1: @a set stays as it is). Deterministic order:
/// the kernels kept in their order, then the samples in tree order. @a progress: one unit per
/// leaf node of cells; throws Cancelled.
Refinement refineKernels(const GridSource::Impl& grid, int n, double alpha, float cutoff, const LevelOfDetail& scale,
    KernelSet& set, openvdb::MaskGrid& sampled, Progress* progress = nullptr, double budget = kRefinedKernelBudget);

} // namespace detail
} // namespace vdb_ewa
