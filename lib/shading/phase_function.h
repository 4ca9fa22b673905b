/// @file phase_function.h
/// @brief The Henyey-Greenstein phase function (Henyey and Greenstein, "Diffuse radiation in the
///        galaxy", 1941; Cycles' Principled Volume calls g Anisotropy), relative to the isotropic
///        phase 1/(4 pi) that vdb_render's single scattering folds into a light's colour x
///        albedo (OpticalModel): g = 0 is 1 exactly, today's image. Issue 56's seam: the
///        compositors and the reference integrators will weigh each light by it.
#pragma once

#include <algorithm>
#include <cmath>

namespace vdb_ewa {
namespace detail {

/// 4 pi p_HG(cos t) = (1 - g^2) / (1 + g^2 - 2 g cos t)^(3/2), for -1 < g < 1 (at +-1 a delta):
/// the radiance scattered towards the eye relative to isotropic scattering. @a cosTheta: the
/// cosine of the scattering angle, between the direction the light travels and the one towards
/// the eye; for a directional light whose
/// direction (towards it) is L seen along a pixel's ray d (from the eye), cos t = L . d: g > 0
/// scatters forwards, so a volume between the eye and the light glows at its edges.
inline double henyeyGreenstein(double cosTheta, double g)
{
    if (g == 0.0) return 1.0;
    const double c = std::clamp(cosTheta, -1.0, 1.0);
    const double denominator = 1.0 + g * g - 2.0 * g * c;
    return (1.0 - g * g) / (denominator * std::sqrt(denominator));
}

/// The cosine of a scattering angle drawn from the Henyey-Greenstein phase of anisotropy @a g
/// for a uniform @a u in [0, 1): the inverse of its cumulative distribution in cos t (for the
/// path tracer's bounces); uniform in [-1, 1] at g = 0.
inline double sampleHenyeyGreenstein(double g, double u)
{
    if (std::abs(g) < 1e-6) return 1.0 - 2.0 * u;
    const double s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
    return std::clamp((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0);
}

} // namespace detail
} // namespace vdb_ewa
