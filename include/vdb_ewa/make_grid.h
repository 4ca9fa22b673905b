/// @file make_grid.h
/// @brief The project's own sample fog grids (grids/README.md): one smooth analytic cloud
///        seen through four kinds of index-to-world map, so every covariance path is exercised.
#pragma once

#include <string>

#include "grid_source.h"

namespace vdb_ewa {

enum class SampleGrid
{
    Cloud,       ///< uniform voxels
    Anisotropic, ///< voxel scale 1:2:4
    Sheared,     ///< rotated and sheared affine map
    Tiles        ///< uniform voxels, density doubled (clamped to the peak) so its core is stored as active tiles
};

/// Parse "cloud", "anisotropic", "sheared", "tiles". @throw ValueError otherwise.
VDB_EWA_API SampleGrid sampleGridFromName(const std::string& name);

/// Density of the analytic cloud at a world position (world units; about 2 units across,
/// centred on the origin). Values in [0, 0.35].
VDB_EWA_API double sampleCloudDensity(const Vec3d& pWorld);

/// Build a sample grid in memory. @a voxelSize is the smallest voxel edge in world units.
VDB_EWA_API GridSource makeSampleGrid(SampleGrid kind, double voxelSize = 0.04);

/// Build a sample grid and write it to @a path (grid name "density"). @throw IoError.
VDB_EWA_API void writeSampleGrid(SampleGrid kind, const std::string& path, double voxelSize = 0.04);

} // namespace vdb_ewa
