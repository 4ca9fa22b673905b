/// @file slab_share.h
/// @brief Image-aligned sheet buffers (Mueller & Crawfis 1998): the share of a kernel's
///        integral along the viewing ray that falls in each slab, and the exact update of a
///        homogeneous slab (ewa-brief Sec. 5).
#pragma once

#include <cmath>
#include <cstdint>

#include "export.h"

namespace vdb_ewa {

/// Standard normal cumulative distribution.
inline double normalCdf(double x) { return 0.5 * std::erfc(-x * 0.70710678118654752440); }

/// Slabs [zBase + k * thickness, zBase + (k + 1) * thickness) along the viewing ray.
struct SlabGrid
{
    double zBase = 0.0;
    double thickness = 1.0;

    std::int64_t index(double z) const { return std::int64_t(std::floor((z - zBase) / thickness)); }
    double start(std::int64_t k) const { return zBase + double(k) * thickness; }
};

/// The depth range [lo, hi] of a Gaussian truncated to mu +- truncation * sd and clipped to
/// [clipNear, clipFar]; false if that range is empty.
inline bool clippedDepthRange(double mu, double sd, double truncation, double clipNear, double clipFar,
    double& lo, double& hi)
{
    lo = mu - truncation * sd > clipNear ? mu - truncation * sd : clipNear;
    hi = mu + truncation * sd < clipFar ? mu + truncation * sd : clipFar;
    return hi > lo;
}

/// Slabs overlapped by mu +- truncation * sd clipped to [clipNear, clipFar]: sets @a first
/// and returns their number (0 if the clipped range is empty).
VDB_EWA_API std::int64_t slabSpan(const SlabGrid& slabs, double mu, double sd, double truncation,
    double clipNear, double clipFar, std::int64_t& first);

/// Shares of a Gaussian of mean @a mu and std. deviation @a sd (along the ray) in each slab
/// it overlaps: Phi((z1 - mu)/sd) - Phi((z0 - mu)/sd). The Gaussian is truncated to
/// mu +- truncation * sd and renormalised, so the shares of an unclipped kernel sum to 1; the
/// part outside [clipNear, clipFar] (near and far planes) is dropped, not redistributed.
/// Writes at most @a maxCount shares to @a shares and the first slab index to @a first. With
/// @a moments (2 floats a share), also where each share lies in its slab: the mean and the
/// mean square of the position of the Gaussian restricted to the slab (a truncated normal:
/// mean mu + sd (phi(a) - phi(b)) / Z, variance sd^2 (1 + (a phi(a) - b phi(b)) / Z - ((phi(a) -
/// phi(b)) / Z)^2), Z = Phi(b) - Phi(a)), in units of the slab's thickness from its front.
/// @return the number of slabs written (0 if the kernel lies outside the clip range).
VDB_EWA_API int slabShares(const SlabGrid& slabs, double mu, double sd, double truncation,
    double clipNear, double clipFar, std::int64_t& first, float* shares, int maxCount, float* moments = nullptr);

/// The fraction of light a slab of optical depth @a tau absorbs, 1 - exp(-tau) (0 for tau <= 0).
inline float slabAbsorbed(float tau) { return tau > 0.0f ? -std::expm1(-tau) : 0.0f; }

/// A homogeneous slab's own emitted light from its extinction-weighted emission @a emission:
/// (E / tau)(1 - exp(-tau)), E itself where tau is too small to divide by. @a absorbed:
/// slabAbsorbed(tau).
inline float slabEmitted(float tau, float absorbed, float emission)
{
    return emission == 0.0f ? 0.0f : (tau > 1e-7f ? emission / tau * absorbed : emission);
}

/// Exact front-to-back update of one homogeneous slab for one colour channel: optical depth
/// @a tau, extinction-weighted emission @a emission (= sum of colour x optical depth), and
/// @a scattered, a source already integrated across the slab (the scattering weight x the
/// light's colour x slabLightIntegral):
/// C += T ((E / tau)(1 - exp(-tau)) + scattered); T *= exp(-tau). @a absorbed: slabAbsorbed(tau).
/// Without optical depth (emission grids where there is no density) C += T E.
inline void compositeSlab(float tau, float absorbed, float emission, float scattered, float& colour, float& transmittance)
{
    if (!(tau > 0.0f)) {
        if (emission > 0.0f) colour += transmittance * emission;
        return;
    }
    colour += transmittance * (slabEmitted(tau, absorbed, emission) + scattered);
    transmittance *= 1.0f - absorbed;
}

inline void compositeSlab(float tau, float emission, float& colour, float& transmittance)
{
    compositeSlab(tau, slabAbsorbed(tau), emission, 0.0f, colour, transmittance);
}

/// E(x) = (1 - e^-x) / x, the mean of e^(-x u) over u in [0, 1]; below |x| = 1e-3 its series
/// to x^2 (error x^3 / 24 < 1e-10).
inline float slabMeanOfExp(float x)
{
    return std::abs(x) < 1e-3f ? 1.0f - x * (0.5f - x / 6.0f) : -std::expm1(-x) / x;
}

/// The least light the slab integrals use: values of the light's transmittance below it count
/// as it (slabLightIntegral, slabLightTransmittance), and its logarithm floors lightLogRatio's.
inline constexpr float kLightFloor = 1e-30f;
inline constexpr float kLogLightFloor = -69.0775528f; ///< ln kLightFloor

/// The light a uniform layer of optical depth @a tau (one channel) scatters towards the eye per
/// unit scattering weight and light colour, when the light's transmittance along the viewing
/// ray falls exponentially from @a front at the layer's front by @a logRatio = k =
/// ln(front / back) across it (linear light optical depth, as between two light-map samples):
/// int_0^1 T_L(u) e^(-tau u) du = front E(tau + k), T_L(u) = front e^(-k u). @a logRatio is the
/// light's optical depth between the layer's back and front, known without a log where that
/// optical depth is (lightLogRatio). compositeSlab's @a scattered is the scattering weight x the
/// light's colour x this (docs/numerics.md#shading-per-slab-sample). In single precision (once
/// per lit pixel and slab): 1e-6 relative. Values of the light below 1e-30 count as 1e-30, in
/// @a front and in both logarithms behind @a logRatio.
inline float slabLightIntegral(float tau, float front, float logRatio)
{
    return (front > kLightFloor ? front : kLightFloor) * slabMeanOfExp((tau > 0.0f ? tau : 0.0f) + logRatio);
}

/// ln(front / back) for slabLightIntegral from the logarithms of the light's transmittance at
/// the layer's front and back (each floored at ln 1e-30).
inline float lightLogRatio(float logFront, float logBack)
{
    return (logFront > kLogLightFloor ? logFront : kLogLightFloor) - (logBack > kLogLightFloor ? logBack : kLogLightFloor);
}

/// The light transmittance that, used as one value for the whole slab, lights the same layer
/// as slabLightIntegral, with the light given at the layer's front and back: compositeSlab(tau,
/// a S T) then adds T a S int_0^1 T_L(u) e^(-tau u) du. The value is front E(tau + k) / E(tau):
/// the light at the layer's front where it is optically thick (it is seen only there), the mean
/// of the exponential where it is thin.
inline float slabLightTransmittance(float tau, float front, float back)
{
    const float f = front > kLightFloor ? front : kLightFloor, b = back > kLightFloor ? back : kLightFloor;
    return slabLightIntegral(tau, f, std::log(f / b)) / slabMeanOfExp(tau > 0.0f ? tau : 0.0f);
}

/// Where a homogeneous slab's mean transmittance, falling exponentially from @a before at its
/// front to @a after at its back, reaches 0.5 (alpha 0.5, the Z pass): the fraction of the
/// slab's thickness, in [0, 1], or 2 if it stays above 0.5. Exact for grey media.
inline double halfAlphaFraction(float before, float after)
{
    if (!(after <= 0.5f)) return 2.0;
    if (!(before > 0.5f) || !(after > 0.0f)) return 0.0;
    return std::log(double(before) / 0.5) / std::log(double(before) / double(after));
}

} // namespace vdb_ewa
