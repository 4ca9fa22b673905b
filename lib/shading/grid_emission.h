/// @file grid_emission.h
/// @brief Emission from grids, as a pyro cache is lit: an emission grid (its value x colour x
///        intensity) and blackbody emission of a temperature grid (physically based colour and
///        radiance), as radiance per voxel length wherever they are, whatever the density
///        (docs/equations.md#emission-grids). The reference samples them (EmissionSampler); the
///        splatter gives them kernels of their own (emitterKernels), with no optical depth.
#pragma once

#include "source/source.h"
#include "support/memory_budget.h"
#include "support/progress.h"
#include "support/rgb.h"

#include <vdb_ewa/render_settings.h>

#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// The most radiance per voxel length an emission grid gives (a channel, or a blackbody's
/// luminance): as the medium's coefficients, opaque-scale and inside float's range.
constexpr double kMaxRadiance = 1e6;

/// Blender's unit: Cycles' Principled Volume emits 1e-6 sigma T^4 / pi per unit length at
/// Blackbody Intensity 1 (intern/cycles/kernel/svm/closure.h); vdb_ewa, per voxel length.
constexpr double kBlackbodyUnit = 1e-6;

/// The emission settings (RenderSettings::gridEmission) turned into radiance.
class EmissionModel
{
public:
    explicit EmissionModel(const RenderSettings& settings);

    /// An emission-grid value's radiance per voxel length: value x colour x intensity, at most
    /// kMaxRadiance a channel.
    Vec3d emitted(double value) const { return value > 0.0 ? glm::min(value * mColour, Vec3d(kMaxRadiance)) : Vec3d(0.0); }
    /// The Kelvin of a temperature-grid value: value x kelvinScale + kelvinOffset.
    double kelvin(double value) const { return value * mScale + mOffset; }
    /// The luminance (Y) of a blackbody at a temperature-grid value, per voxel length:
    /// intensity x kBlackbodyUnit x sigma T^4 / pi (0 at or below 0 K), at most kMaxRadiance.
    double blackbodyLuminance(double value) const;
    /// The working-space colour of luminance 1 of a blackbody at a temperature-grid value
    /// (negative components, outside the working space's gamut, 0): a table over log Kelvin,
    /// within 1e-4 of blackbodyXyz.
    Vec3d blackbodyColour(double value) const;
    /// blackbodyLuminance x blackbodyColour.
    Vec3d blackbody(double value) const { return blackbodyLuminance(value) * blackbodyColour(value); }

private:
    Vec3d mColour;
    double mScale, mOffset, mIntensity;
    std::vector<Vec3d> mTable; ///< colours at kTableKelvinMin x kTableRatio^i
};

/// Below this a blackbody's radiance is under 1/600 of 1000 K's (T^4): a hottestKelvin below it
/// draws a warning.
constexpr double kVisibleKelvin = 200.0;

/// Radiance per voxel length of a grid's emission and temperature grids at index-space points
/// of the grid (trilinear lookups, then the model: post-classification, as vdb_render would).
/// Holds accessors: one per thread; @a model, built once per frame, is shared (null: the grid
/// has no emission or temperature grid).
class EmissionSampler
{
public:
    EmissionSampler(const GridSource::Impl& grid, const EmissionModel* model);

    /// True if the grid has an emission or a temperature grid.
    bool any() const { return mEmission.has_value() || mTemperature.has_value(); }
    /// The radiance at @a pIndex; 0 in a cell with no active temperature voxel at its corners
    /// (empty space stays dark whatever --temperature-offset says, as in the splatter).
    Vec3d at(const Vec3d& pIndex);

private:
    const EmissionModel* mModel;
    std::optional<openvdb::FloatGrid::ConstAccessor> mEmission, mTemperature;
    std::optional<openvdb::Vec3SGrid::ConstAccessor> mEmissionColor; ///< GridSource::Impl::emissionColor
};

/// The splatter's kernels of a grid's emission and temperature grids, none without either:
/// each emitting grid's active voxels (values sanitised as a density's, GridSource::Impl::field)
/// become kernels with quasi-interpolating weights like the density's; the temperature grid's
/// carry each voxel's mean blackbody luminance (of the trilinear temperature, over the voxel and
/// the shell it spreads into); @c radiance is each kernel's colour per unit weight (the emission
/// colour, or its voxel's blackbody colour; a refined sample's, its point's). With @a lod,
/// blocks merge where the density's do (LevelSource), so that emission and density keep the
/// same kernel shapes. In the grid's index space.
struct EmitterKernels
{
    KernelSet kernels;
    std::vector<Rgb> radiance;
    /// The hottest Kelvin of the temperature grid's active values under the mapping (NaN
    /// without a temperature grid or active values): a lighter's check that it glows.
    double hottestKelvin = std::numeric_limits<double>::quiet_NaN();
    /// The refined emitters' lattice was coarsened to fit the budget.
    bool refinementLowered = false;
};

/// The density's refinement (refineKernels) as the emitters follow it: the lattice n and the
/// voxels it sampled; and the kernels the renderer already holds (the density's), which the
/// refined emitters' budget leaves room for.
struct EmitterRefinement
{
    int n = 1;
    const openvdb::MaskGrid* sampled = nullptr;
    std::uint64_t kernelsHeld = 0;
};

/// Refined emitters (with @a lod: the pixels a voxel spans): the emitter kernels of the voxels
/// whose source function (light over density) is steep where the density is thick (on lattices
/// up to --refine-emission, SplatOptions::refineEmission), and of the voxels the density's
/// refinement sampled (@a refined; up to the finer of it and --refine-emission), are replaced by
/// the light itself sampled every 1/n voxel: the emission value, or the blackbody of the
/// trilinear temperature, at each point, with its own colour (docs/lighting.md#emission-at-dense-
/// hot-edges-and-refined-emitters). Both grids' samples within a quarter of @a budget, the finest lattice coarsened
/// to fit (refinementLowered).
EmitterKernels emitterKernels(const GridSource::Impl& grid, const RenderSettings& settings, const LevelOfDetail* lod = nullptr,
    Progress* progress = nullptr, const MemoryBudget* budget = nullptr, const EmitterRefinement& refined = {});

} // namespace detail
} // namespace vdb_ewa
