/// @file array_grid.h
/// @brief A numpy array as a grid to render: voxel (i, j, k) = array[i, j, k] (pyopenvdb's
///        copyFromArray layout), placed in the world by a 4x4 index-to-world matrix.
#pragma once

#include <vdb_ewa/grid_source.h>

#include <pybind11/numpy.h>

#include <string>

namespace vdb_ewa::python {

/// A 4x4 matrix argument (numpy array or nested sequences), column vectors, as the library's
/// Mat4d; None: the identity. @throw ValueError unless 4x4 and finite (GridSource::transformed checks the rest).
Mat4d objectToWorld(const pybind11::object& matrix);

/// The grid @a name of @a values (3D, any real dtype; values equal to 0 are inactive, as
/// pyopenvdb's copyFromArray with tolerance 0), its index-to-world map @a indexToWorld: 4x4,
/// column vectors (world = M @ (i, j, k, 1), numpy's and Blender's convention), affine (last
/// row 0, 0, 0, 1) and invertible; None: the identity.
/// @throw ValueError naming the argument (wrong shape, non-finite or singular matrix).
GridSource gridFromArray(const pybind11::array& values, const pybind11::object& indexToWorld, const std::string& name);

/// @a grid with the emission or temperature grid @a values on @a grid's voxels (the same shape
/// and transform as the density array). @a kind: "emission" or "temperature".
GridSource withArrayEmitter(const GridSource& grid, const pybind11::array& values, const pybind11::object& indexToWorld,
    const std::string& kind);

/// @a grid with motion blur from the velocity array @a values, shaped (the density's shape, 3):
/// the vector at [i, j, k] in world units per second or frame (render's velocity_unit), on the
/// density's voxels and transform. @throw ValueError for another shape.
GridSource withArrayVelocity(const GridSource& grid, const pybind11::array& values, const pybind11::object& indexToWorld);

} // namespace vdb_ewa::python
