/// @file scattering_octaves.h
/// @brief Multiple scattering by octaves (Wrenninge, Kulla and Lundqvist, "Oz: The Great and
///        Volumetric", SIGGRAPH 2013; Hillaire 2016): octave i scatters a light again with the
///        scattering scaled by a^i, the light's optical depth by b^i and the anisotropy by c^i,
///        so light that went deep (a dim single-scattering term) still reaches the eye as the
///        softer, brighter glow many bounces give. Every octave reads the same light map: its
///        transmittance is T^(b^i). Octave 0 is single scattering with the Henyey-Greenstein
///        phase (phase_function.h); one octave at g = 0 is vdb_render's model exactly
///        (docs/lighting.md#scattering).
#pragma once

#include "shading/phase_function.h"

#include <vdb_ewa/render_settings.h>

#include <cmath>

namespace vdb_ewa {
namespace detail {

class ScatteringOctaves
{
public:
    explicit ScatteringOctaves(const Scattering& s = Scattering()) : mCount(s.octaves)
    {
        double a = 1.0, b = 1.0, g = s.anisotropy;
        for (int i = 0; i < mCount && i < kMax; ++i) {
            mScatter[i] = a;
            mExtinction[i] = b;
            mAnisotropy[i] = g;
            a *= s.octaveScatter;
            b *= s.octaveExtinction;
            g *= s.octaveAnisotropy;
        }
    }

    static constexpr int kMax = 16;

    /// Octaves carried (1: single scattering).
    int count() const { return mCount; }
    /// False where the light is vdb_render's: one isotropic octave, every weight 1 and every
    /// transmittance the light map's own (the shaders skip the octaves' arithmetic).
    bool shaped() const { return mCount > 1 || mAnisotropy[0] != 0.0; }
    /// Octave @a i's weight for a scattering angle of cosine @a cosTheta: a^i x its phase
    /// relative to isotropic (henyeyGreenstein with anisotropy c^i g).
    double weight(int i, double cosTheta) const { return mScatter[i] * henyeyGreenstein(cosTheta, mAnisotropy[i]); }
    /// Octave @a i's factor on the light's optical depth (and log transmittance): b^i.
    double extinction(int i) const { return mExtinction[i]; }

    /// The light scattered towards the eye per unit of single scattering's isotropic light, for
    /// a light of transmittance @a transmittance at the sample seen at cosine @a cosTheta:
    /// sum over the octaves of a^i phase_i(cos t) T^(b^i) (the reference's, per sample).
    double response(double cosTheta, double transmittance) const
    {
        if (!shaped()) return transmittance;
        double sum = 0.0;
        for (int i = 0; i < mCount; ++i) {
            const double t = mExtinction[i] == 1.0 ? transmittance : transmittance > 0.0 ? std::pow(transmittance, mExtinction[i]) : 0.0;
            sum += weight(i, cosTheta) * t;
        }
        return sum;
    }

private:
    int mCount;
    double mScatter[kMax] = {}, mExtinction[kMax] = {}, mAnisotropy[kMax] = {};
};

} // namespace detail
} // namespace vdb_ewa
