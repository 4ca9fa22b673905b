/// @file blackbody.h
/// @brief Blackbody emission from first principles: the colour of Planck's law seen by the CIE 1931
///        2 degree observer (chromaticity only, Y = 1) and its total radiance (Stefan-Boltzmann),
///        kept apart so that an intensity convention can be applied on top. Blender Cycles'
///        Principled Volume, for one, emits tint x (sigma 1e-6 / pi) T^4 x a Rec.709 colour of
///        luminance 1, not scaled by density (intern/cycles/kernel/svm/closure.h,
///        svm_node_principled_volume).
#pragma once

#include <vdb_ewa/types.h>

namespace vdb_ewa {
namespace detail {

/// CIE 1931 XYZ of a blackbody at @a kelvin, normalised to Y = 1: Planck's spectral radiance
/// 2hc^2 / lambda^5 / (exp(hc / (lambda k T)) - 1) (CODATA 2018 h, c, k) summed against the
/// tabulated colour-matching functions, 360..830 nm every 5 nm. Zero for @a kelvin <= 0 or not
/// finite. Finite for any other temperature: below 1 K the colour is that of 830 nm to double
/// precision, and 1 K is used. About a hundred exponentials: cheap enough per voxel.
Vec3d blackbodyXyz(double kelvin);

/// Total radiance of a blackbody, sigma T^4 / pi (W m^-2 sr^-1), sigma = 5.670374419e-8
/// W m^-2 K^-4 (CODATA 2018). Zero for @a kelvin <= 0 or not finite; overflows to infinity past
/// about 1e77 K.
double blackbodyRadiance(double kelvin);

/// CIE XYZ -> linear Rec.709 / sRGB primaries, D65 white (IEC 61966-2-1; the matrix as printed by
/// Lindbloom, brucelindbloom.com "RGB/XYZ Matrices"). Rows are R, G, B.
inline const Mat3d kXyzToLinearRec709 = mat3FromRows({3.2404542, -1.5371385, -0.4985314},
                                                     {-0.9692660, 1.8760108, 0.0415560},
                                                     {0.0556434, -0.2040259, 1.0572252});

/// @a xyz in linear Rec.709 (kXyzToLinearRec709 * xyz). Blackbodies fall outside the Rec.709
/// gamut below about 1900 K (B < 0) and 965 K (G < 0 too); clamping is the caller's choice.
inline Vec3d xyzToLinearRec709(const Vec3d& xyz)
{
    return kXyzToLinearRec709 * xyz;
}

} // namespace detail
} // namespace vdb_ewa
