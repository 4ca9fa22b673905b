/// @file array_grid.cpp
#include "array_grid.h"

#include <vdb_ewa/error.h>

// OpenVDB keeps the default visibility it was built with (lib/support/openvdb.h explains why);
// pybind11 compiles the module hidden.
#pragma GCC visibility push(default)
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>
#pragma GCC visibility pop
#include <vdb_ewa/openvdb_grid.h>

#include <cmath>

namespace py = pybind11;

namespace vdb_ewa::python {
namespace {

/// The 4x4 matrix @a m (a numpy array or nested sequences), finite. @throw ValueError naming @a argument
Mat4d matrix4(const py::object& m, const std::string& argument)
{
    const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(m);
    if (!a || a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4) throw ValueError(argument + ": expected a 4x4 matrix");
    Mat4d out;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) {
            out[c][r] = a.at(r, c); // GLM: out[column][row]
            if (!std::isfinite(out[c][r])) throw ValueError(argument + ": a matrix element is not finite");
        }
    return out;
}

/// @a m as OpenVDB's row-vector matrix (its transpose), checked: affine and invertible.
openvdb::math::Mat4d indexToWorldMatrix(const py::object& m)
{
    openvdb::math::Mat4d rowVector = openvdb::math::Mat4d::identity();
    if (m.is_none()) return rowVector;
    const Mat4d columns = matrix4(m, "index_to_world");
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) rowVector(c, r) = columns[c][r];
    if (columns[0][3] != 0.0 || columns[1][3] != 0.0 || columns[2][3] != 0.0 || columns[3][3] != 1.0) {
        throw ValueError("index_to_world: the last row must be 0, 0, 0, 1 (column vectors: world = M @ (i, j, k, 1); a "
                         "row-vector matrix, OpenVDB's, is its transpose)");
    }
    const double det = rowVector.getMat3().det();
    if (!(std::abs(det) > 1e-300)) throw ValueError("index_to_world: the matrix is singular (a voxel of no volume)");
    return rowVector;
}

/// The grid of C-ordered float data @a dense shaped [i, j, k] (scalars) or [i, j, k, 3] (Vec3s
/// values): voxels equal to zero inactive, placed by @a indexToWorld.
template <typename GridType>
typename GridType::Ptr gridFromDense(const py::array_t<float, py::array::c_style | py::array::forcecast>& dense, const py::object& indexToWorld)
{
    using Value = typename GridType::ValueType;
    const openvdb::math::Mat4d matrix = indexToWorldMatrix(indexToWorld);
    const openvdb::CoordBBox box(openvdb::Coord(0), openvdb::Coord(int(dense.shape(0)) - 1, int(dense.shape(1)) - 1, int(dense.shape(2)) - 1));
    auto grid = GridType::create(Value(0.0f));
    {
        py::gil_scoped_release release; // large arrays take a while; the array stays alive
        // LayoutZYX: z varies fastest, as a C-ordered array [i, j, k] (of xyz for a vector).
        const openvdb::tools::Dense<Value, openvdb::tools::LayoutZYX> view(box, reinterpret_cast<Value*>(const_cast<float*>(dense.data()))); // read only
        openvdb::tools::copyFromDense(view, *grid, Value(0.0f));
    }
    grid->setTransform(openvdb::math::Transform::createLinearTransform(matrix));
    return grid;
}

openvdb::FloatGrid::Ptr floatGrid(const py::array& values, const py::object& indexToWorld, const std::string& argument)
{
    const auto dense = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(values);
    if (!dense || dense.ndim() != 3) throw ValueError(argument + ": expected a 3D array of numbers, indexed [i, j, k]");
    if (dense.size() == 0) throw ValueError(argument + ": the array is empty");
    return gridFromDense<openvdb::FloatGrid>(dense, indexToWorld);
}

} // namespace

Mat4d objectToWorld(const py::object& matrix)
{
    return matrix.is_none() ? Mat4d(1.0) : matrix4(matrix, "object_to_world");
}

GridSource gridFromArray(const py::array& values, const py::object& indexToWorld, const std::string& name)
{
    openvdb::initialize();
    openvdb::FloatGrid::Ptr grid = floatGrid(values, indexToWorld, "array");
    grid->setName(name);
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    return gridSourceFromOpenVDB(grid);
}

GridSource withArrayEmitter(const GridSource& grid, const py::array& values, const py::object& indexToWorld, const std::string& kind)
{
    openvdb::FloatGrid::Ptr emitter = floatGrid(values, indexToWorld, kind);
    emitter->setName(kind);
    return kind == "emission" ? withEmissionGrid(grid, emitter) : withTemperatureGrid(grid, emitter);
}

GridSource withArrayVelocity(const GridSource& grid, const py::array& values, const py::object& indexToWorld)
{
    const auto dense = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(values);
    if (!dense || dense.ndim() != 4 || dense.shape(3) != 3) throw ValueError("velocity: expected an array of the density's shape and 3 components, [i, j, k, xyz]");
    openvdb::Vec3SGrid::Ptr velocity = gridFromDense<openvdb::Vec3SGrid>(dense, indexToWorld);
    velocity->setName("velocity");
    return withVelocityGrid(grid, velocity);
}

} // namespace vdb_ewa::python
