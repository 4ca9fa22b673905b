/// @file material_color.h
/// @brief Material colour from a GridSource's colour grid (vdb_render's -color): the level-set
///        shaders and the fog volume's scattering albedo multiply by it.
#pragma once

#include "source/grid_source_impl.h"
#include "source/kernel_extraction.h"
#include "support/rgb.h"

#include <optional>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// Trilinear lookups into the colour grid at world positions; white without one. Holds an
/// accessor: one per thread.
class MaterialColor
{
public:
    explicit MaterialColor(const GridSource::Impl& grid);

    /// The colour at @a pWorld, as the grid holds it (the input space); non-finite and negative
    /// components read as 0.
    Vec3d at(const Vec3d& pWorld);

private:
    const GridSource::Impl& mGrid;
    std::optional<openvdb::Vec3SGrid::ConstAccessor> mAccessor;
};

/// An input-space colour (the colour grid's, a level-set shader's) in the working space:
/// RenderSettings::inputToWorking times it, negative components (outside the working space's
/// gamut) taken as 0.
Vec3d workingColor(const Mat3d& inputToWorking, const Vec3d& color);

/// The colour at every kernel's centre in the working space (@a inputToWorking), in kernel
/// order; empty without a colour grid.
std::vector<Rgb> kernelColors(const GridSource::Impl& grid, const KernelSet& kernels, const Mat3d& inputToWorking);

} // namespace detail
} // namespace vdb_ewa
