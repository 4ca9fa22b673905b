/// @file optical_model.h
/// @brief The optical model, in one place: every integrator (the splatter's kernels, the
///        reference's ray samples) asks it for optical depth and source radiance, so they cannot
///        disagree by construction. vdb_render's model (OpenVDB tools/RayTracer.h,
///        VolumeRender): extinction (absorb + scatter) x density per voxel length, single
///        scattering of directional lights, each attenuated by its shadow transmittance, plus an
///        unshadowed ambient light and self-emission (docs/equations.md#optical-model).
#pragma once

#include <vdb_ewa/render_settings.h>

#include "shading/scattering_octaves.h"
#include "support/rgb.h"

#include <array>
#include <vector>

namespace vdb_ewa {
namespace detail {

class OpticalModel
{
public:
    explicit OpticalModel(const RenderSettings& settings)
        : mOctaves(settings.scattering), mLightScale(settings.lights.size()), mPointScale(settings.pointLights.size())
    {
        for (int c = 0; c < 3; ++c) {
            mExtinction[c] = settings.medium.extinction()[c];
            const bool scatters = mExtinction[c] > 0.0;
            for (std::size_t l = 0; l < mLightScale.size(); ++l) {
                mLightScale[l][std::size_t(c)] = scatters ? settings.lights[l].color[c] * settings.medium.scatter[c] / mExtinction[c] : 0.0;
            }
            for (std::size_t l = 0; l < mPointScale.size(); ++l) {
                mPointScale[l][std::size_t(c)] = scatters ? settings.pointLights[l].color[c] * settings.medium.scatter[c] / mExtinction[c] : 0.0;
            }
            mEmitted[c] = scatters ? settings.medium.emission[c] / mExtinction[c] : 0.0;
            mAmbient[c] = scatters ? settings.ambient[c] * settings.medium.scatter[c] / mExtinction[c] : 0.0;
        }
    }

    /// The phase function and the octaves of multiple scattering (docs/lighting.md#scattering):
    /// every light but the ambient is weighed by them.
    const ScatteringOctaves& octaves() const { return mOctaves; }

    /// sigma_t of channel @a c: optical depth per unit density per voxel length.
    double extinction(int c) const { return mExtinction[c]; }

    /// Optical depth of density @a density over @a voxelLengths (Eq. 7's integral of g).
    double opticalDepth(int c, double density, double voxelLengths) const
    {
        return mExtinction[c] * density * voxelLengths;
    }

    /// The directional lights (RenderSettings::lights), in order.
    std::size_t lightCount() const { return mLightScale.size(); }

    /// Light @a l's colour x scattering albedo of channel @a c: the source radiance per unit
    /// optical depth it gives white material in full light.
    double lightScale(std::size_t l, int c) const { return mLightScale[l][std::size_t(c)]; }

    /// The point and spot lights (RenderSettings::pointLights), in order.
    std::size_t pointLightCount() const { return mPointScale.size(); }
    /// Point light @a l's intensity x scattering albedo of channel @a c: its source radiance
    /// per unit optical depth in white material at unit falloff (pointLightFalloff), unshadowed.
    double pointScale(std::size_t l, int c) const { return mPointScale[l][std::size_t(c)]; }
    /// True if point light @a l scatters nothing: it needs no light map.
    bool pointDark(std::size_t l) const { return mPointScale[l][0] == 0.0 && mPointScale[l][1] == 0.0 && mPointScale[l][2] == 0.0; }

    /// Source radiance per unit optical depth (the c of Eq. 7 and 10): each light's colour x
    /// scattering albedo x material colour x its transmittance @a lightTransmittances[l]
    /// (one per light), summed, plus the ambient light scattered (ambient()), plus emission /
    /// extinction.
    double source(int c, const Rgb* lightTransmittances, double materialColor) const
    {
        return scattered(c, lightTransmittances, materialColor) + ambient(c, materialColor) + mEmitted[c];
    }

    /// The ambient light scattered per unit optical depth: ambient x scattering albedo x
    /// material colour. Never shadowed, so the splatter carries it with the emission.
    double ambient(int c, double materialColor) const { return mAmbient[c] * materialColor; }

    /// The lights' part of source() alone.
    double scattered(int c, const Rgb* lightTransmittances, double materialColor) const
    {
        double sum = 0.0;
        for (std::size_t l = 0; l < mLightScale.size(); ++l) {
            sum += mLightScale[l][std::size_t(c)] * materialColor * double(lightTransmittances[l][std::size_t(c)]);
        }
        return sum;
    }

    /// The emission part of source() alone (the emission pass).
    double emitted(int c) const { return mEmitted[c]; }

    /// True if no light scatters: the shadow transmittance is never used.
    bool unlit() const
    {
        for (const auto& scale : mLightScale) {
            if (scale[0] != 0.0 || scale[1] != 0.0 || scale[2] != 0.0) return false;
        }
        return true;
    }

    /// True if light @a l scatters nothing (black, or nothing scatters): it needs no light map.
    bool dark(std::size_t l) const { return mLightScale[l][0] == 0.0 && mLightScale[l][1] == 0.0 && mLightScale[l][2] == 0.0; }

private:
    ScatteringOctaves mOctaves;
    double mExtinction[3], mEmitted[3], mAmbient[3];
    std::vector<std::array<double, 3>> mLightScale; ///< per light: colour x scatter / extinction
    std::vector<std::array<double, 3>> mPointScale; ///< per point light: intensity x scatter / extinction
};

} // namespace detail
} // namespace vdb_ewa
