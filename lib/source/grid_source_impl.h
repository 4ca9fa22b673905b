/// @file grid_source_impl.h
/// @brief The OpenVDB side of GridSource (private).
#pragma once

#include <vdb_ewa/grid_source.h>
#include <vdb_ewa/render_settings.h>

#include <vector>

#include "support/openvdb.h"

namespace vdb_ewa {
namespace detail {

/// Densities above this are clamped: a voxel this dense is opaque at any sane setting.
constexpr float kMaxDensity = 1.0e6f;

} // namespace detail

struct VDB_EWA_LOCAL GridSource::Impl
{
    /// Always a float grid: double grids are converted on load (densities need no more).
    openvdb::FloatGrid::ConstPtr grid;
    std::string name;
    std::string path;
    std::string storedType; ///< "float", "half" or "double"
    bool linear = true;
    Mat3d indexToWorldLinear{1.0};   ///< A: linear part of the index-to-world map (affine grids)
    Vec3d indexToWorldOffset{0.0};   ///< world position of index (0, 0, 0) (affine grids)
    double voxelLength = 1.0;        ///< cbrt|det A|: the length "per voxel" densities refer to
    std::uint64_t activeVoxels = 0;  ///< active voxels in leaf nodes
    std::uint64_t activeTiles = 0;
    Vec3d worldCentre{0.0};
    /// Material colours for level-set shaders (vdb_render -color), or null.
    openvdb::Vec3SGrid::ConstPtr color;
    /// Emission grids of fog volumes (GridSource::withEmissionGrid, withTemperatureGrid), in this
    /// grid's index space (resampled where their transform differs), or null.
    std::shared_ptr<const Impl> emission, temperature;
    /// Motion blur's velocities (GridSource::withVelocityGrid), in their own transform, or null;
    /// velocityToWorld takes a stored vector to world space (the moves of transformed()).
    openvdb::Vec3SGrid::ConstPtr velocity;
    Mat3d velocityToWorld{1.0};
    /// The voxel values of the continuous field every integrator reconstructs (its trilinear
    /// interpolation, OpenVDB's BoxSampler; docs/equations.md#the-field): @c grid with NaN,
    /// negative values and inactive values read as 0 and values above kMaxDensity clamped. The
    /// same pointer as @c grid when no value needs that (fog volumes as written by DCCs) and for
    /// level sets.
    openvdb::FloatGrid::ConstPtr field;
    /// The moves of transformed(), composed (column vectors): applied to grids read later.
    Mat4d placement{1.0};

    /// A volume added with an optical model of its own (withAddedVolume(other, medium)): its
    /// density on this grid's voxels, per this grid's voxel length; its medium (input space);
    /// and the volume itself, for its colour, emission and temperature grids.
    struct AddedMaterial
    {
        openvdb::FloatGrid::ConstPtr density;
        Medium medium;
        std::shared_ptr<const Impl> volume;
    };
    /// With volumes of their own optical models: @c field is every volume's density summed (for
    /// the topology, the bounds and the velocities) and this holds the parts; each render mixes
    /// them (detail::mixMaterials). @c ownDensity: the densities that take the render's medium
    /// and this grid's colour and emission grids (this grid's, and volumes added without one).
    std::vector<AddedMaterial> addedMaterials;
    openvdb::FloatGrid::ConstPtr ownDensity;
    /// A mixed frame's emission colour per voxel, multiplying the emission grid's values (the
    /// volumes' own emission colours and constant emission); null: GridEmission's colour.
    openvdb::Vec3SGrid::ConstPtr emissionColor;

    /// Fill the derived fields from @a grid.
    void derive();

    /// World position of an index-space point: A p + offset for affine grids, the grid's
    /// transform otherwise.
    Vec3d indexToWorld(const Vec3d& pIndex) const;
    /// The inverse of indexToWorld.
    Vec3d worldToIndex(const Vec3d& pWorld) const;
};

namespace detail {

/// @a grid resampled trilinearly (OpenVDB's BoxSampler) onto the voxels of @a voxels: a grid of
/// another voxel size or placement read in this one's index space (emission grids, added
/// volumes).
openvdb::FloatGrid::Ptr resampledOnto(const openvdb::FloatGrid& grid, const openvdb::math::Transform& voxels);

/// Jacobian of the index-to-world map at an index position (columns: world image of the
/// index axes).
Mat3d indexToWorldJacobian(const openvdb::math::Transform& xform, const openvdb::Vec3d& pIndex);

/// World length of the longest index axis at an index position (the longest column of
/// indexToWorldJacobian): a voxel's size along its longest side.
double longestIndexAxis(const openvdb::math::Transform& xform, const openvdb::Vec3d& pIndex);

} // namespace detail
} // namespace vdb_ewa
