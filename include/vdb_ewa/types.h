/// @file types.h
/// @brief Vector and matrix aliases shared by the public API (GLM, double precision).
/// @note Matrices follow GLM: column-major storage, column-vector convention (y = M x).
#pragma once

#include <glm/glm.hpp>

#include "export.h"

namespace vdb_ewa {

using Vec2d = glm::dvec2;
using Vec3d = glm::dvec3;
using Mat2d = glm::dmat2;
using Mat3d = glm::dmat3;
using Mat4d = glm::dmat4;

/// Build a 3x3 matrix from its rows (GLM constructors take columns).
inline Mat3d mat3FromRows(const Vec3d& r0, const Vec3d& r1, const Vec3d& r2)
{
    return glm::transpose(Mat3d(r0, r1, r2));
}

} // namespace vdb_ewa
