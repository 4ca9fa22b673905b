/// @file matrix_norm.h
/// @brief The Frobenius norm of a 3x3 matrix: a bound on how far it stretches any vector
///        (|M v| <= |M|_F |v|), used where a grid's transform bounds a kernel's reach.
#pragma once

#include <vdb_ewa/types.h>

#include <cmath>

namespace vdb_ewa {
namespace detail {

/// sqrt of the sum of the squares of @a m's entries: at least its largest singular value.
inline double frobeniusNorm(const Mat3d& m)
{
    return std::sqrt(glm::dot(m[0], m[0]) + glm::dot(m[1], m[1]) + glm::dot(m[2], m[2]));
}

} // namespace detail
} // namespace vdb_ewa
