/// @file halton_points.h
/// @brief Where a reference integrator's rays fall in a pixel: the Halton points of bases 2
///        and 3 (well spread for any count), rotated per pixel (Cranley-Patterson) so that no
///        pattern is shared between pixels. The raymarch reference (--pixel-samples) and the
///        path tracer (--samples) each rotate by their own per-pixel random numbers.
#pragma once

#include <vdb_ewa/types.h>

#include <cmath>
#include <cstdint>

namespace vdb_ewa {
namespace detail {

/// The radical inverse of @a i in base @a b: the Halton sequence's coordinate.
inline double radicalInverse(std::uint32_t i, std::uint32_t b)
{
    double inverse = 0.0, digit = 1.0 / double(b);
    for (; i > 0; i /= b, digit /= double(b)) inverse += double(i % b) * digit;
    return inverse;
}

/// Halton point @a i in [0, 1)^2, rotated by (@a r0, @a r1) in [0, 1)^2.
inline Vec2d rotatedHalton(int i, double r0, double r1)
{
    return Vec2d(std::fmod(radicalInverse(std::uint32_t(i), 2) + r0, 1.0), std::fmod(radicalInverse(std::uint32_t(i), 3) + r1, 1.0));
}

} // namespace detail
} // namespace vdb_ewa
