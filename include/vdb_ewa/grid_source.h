/// @file grid_source.h
/// @brief A scalar volume to render: opened from a .vdb file (float, double or half-stored
///        float grids) or handed over by a host application (see openvdb_grid.h).
/// @note OpenVDB types stay out of this header; the grid lives behind an opaque Impl.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "types.h"

namespace vdb_ewa {

struct Medium;

class VDB_EWA_API GridSource
{
public:
    /// Open @a path and read the grid called @a gridName, or the first scalar floating-point
    /// grid when @a gridName is empty (vdb_render's rule).
    /// @throw IoError    missing, unreadable, non-VDB or truncated file
    /// @throw InputError no such grid, or a grid that is not a scalar float/double grid
    static GridSource open(const std::string& path, const std::string& gridName = "");

    /// The same grid with material colours from the vec3s grid @a colorName of its file
    /// (vdb_render's -color), sampled trilinearly: the level-set shaders multiply by it at each
    /// surface kernel; fog volumes multiply the scattering albedo by it at each kernel (and
    /// the --iso surface's colour). Non-finite and negative components read as 0. @throw IoError, InputError (no such grid, not a vec3s grid, or a
    /// host grid without a file: use withColorGrid in openvdb_grid.h).
    GridSource withColorGrid(const std::string& colorName) const;
    bool hasColorGrid() const;

    /// The same grid with emission from the float grid @a emissionName of its file: its value x
    /// GridEmission's colour and intensity is radiance per voxel length, wherever it is
    /// (a pyro cache's flame). Sampled in this grid's index space: resampled trilinearly where its
    /// transform differs. @throw IoError, InputError (no such grid, not a float grid, or a host
    /// grid without a file: use withEmissionGrid in openvdb_grid.h).
    GridSource withEmissionGrid(const std::string& emissionName) const;
    /// The same grid with blackbody emission from the float grid @a temperatureName of its file
    /// (Kelvin = value x GridEmission::kelvinScale + kelvinOffset), as withEmissionGrid.
    GridSource withTemperatureGrid(const std::string& temperatureName) const;
    bool hasEmissionGrid() const;
    bool hasTemperatureGrid() const;

    /// The same grid with motion blur from the velocity grid @a velocityName of its file: a
    /// vec3s or vec3d grid (Houdini's v or vel), or, where the file has no grid of that name,
    /// the float grids NAME.x, NAME.y and NAME.z (Blender's split vectors). World units per
    /// second or per frame (RenderSettings::motionBlur), sampled trilinearly (staggered grids
    /// as such) at each kernel's centre; non-finite components read as 0.
    /// @throw IoError, InputError (no such grid, the wrong value type, split grids with
    /// different transforms, or a host grid without a file: use withVelocityGrid in openvdb_grid.h).
    GridSource withVelocityGrid(const std::string& velocityName) const;
    bool hasVelocityGrid() const;

    /// This fog volume and the fog volume @a other in one field, their densities summed: both
    /// go through one front-to-back sweep, so where they interpenetrate each hides and shadows
    /// the other (--add-volume). @a other is resampled trilinearly onto this grid's voxels where
    /// its transform differs (name the finest volume first), its densities scaled by the ratio
    /// of the voxel lengths so that its optical depth per world unit is kept (densities are per
    /// voxel length). It brings its density and its velocities (withVelocityGrid, attached to
    /// either before the sum): the sum moves with the mean of both volumes' velocities weighted
    /// by their densities, exact where one volume is alone (a volume without a velocity grid
    /// stands still). Colours and emission are this grid's. The sum is clamped as one density is (1e6).
    /// @throw InputError where either is a level set.
    GridSource withAddedVolume(const GridSource& other) const;

    /// As withAddedVolume(other), @a other with an optical model of its own: @a medium's
    /// absorb, scatter and emission per unit of its density per voxel length, and the colour,
    /// emission and temperature grids attached to @a other (withColorGrid, withEmissionGrid,
    /// withTemperatureGrid) in place of this grid's. Each render mixes the volumes where they
    /// interpenetrate, voxel by voxel, with the render's RenderSettings::medium as this grid's:
    /// extinctions and scattered and emitted light add, each weighed by its own density
    /// (docs/equations.md#volumes-with-optical-models-of-their-own). @a medium's colours are
    /// taken in the input space, as the colour grid's (RenderSettings::inputToWorking). Light
    /// maps march one extinction colour: where a volume's extinction is not in proportion to
    /// this grid's (another hue), the frame is rendered once per channel, every medium grey at
    /// that channel's coefficients (exact, 3x the time; a deep image takes the other hue grey at
    /// its mean; the render says which). @throw InputError as withAddedVolume; ValueError for a negative or non-finite
    /// coefficient.
    GridSource withAddedVolume(const GridSource& other, const Medium& medium) const;

    /// The same grid moved by @a objectToWorld (column vectors: world = M (x, y, z, 1); a DCC
    /// object's transform, e.g. Blender's matrix_world): its index-to-world map is followed by
    /// M, for its colour and emission grids too, and for those attached to the result later.
    /// Affine: the last row 0, 0, 0, 1; any invertible linear part (scales, shears).
    /// @throw ValueError for a non-finite, non-affine or singular matrix.
    GridSource transformed(const Mat4d& objectToWorld) const;

    const std::string& name() const;
    /// File the grid came from, empty for a host grid.
    const std::string& path() const;
    /// "float" or "double": the value type stored in the file (half-stored grids read as float).
    const std::string& storedType() const;
    bool isLevelSet() const;
    /// True if the index-to-world map is affine (one covariance per frame, Eq. 31).
    bool isLinear() const;
    std::uint64_t activeVoxelCount() const;
    std::uint64_t activeTileCount() const;
    /// Centre of the active voxel bounding box in world space (vdb_render's default target).
    Vec3d worldCentre() const;
    /// The length densities are "per" (--absorb, --scatter, --emission): cbrt |det| of the
    /// index-to-world map's linear part (at the centre, for a non-linear map), in world units.
    double voxelLength() const;

    struct Impl;
    explicit GridSource(std::shared_ptr<const Impl> impl) : mImpl(std::move(impl)) {}
    const Impl& impl() const { return *mImpl; }

private:
    std::shared_ptr<const Impl> mImpl;
};

} // namespace vdb_ewa
