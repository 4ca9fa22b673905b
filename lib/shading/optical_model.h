/// @file optical_model.h
/// @brief The optical model, in one place: every integrator (the splatter's kernels, the
///        reference's ray samples) asks it for optical depth and source radiance, so they cannot
///        disagree by construction. vdb_render's model (OpenVDB tools/RayTracer.h,
///        VolumeRender): extinction (absorb + scatter) x density per voxel length, single
///        scattering of one directional light attenuated by the shadow transmittance, plus an
///        unshadowed ambient light and self-emission (docs/equations.md#optical-model).
#pragma once

#include <vdb_ewa/render_settings.h>

namespace vdb_ewa {
namespace detail {

class OpticalModel
{
public:
    explicit OpticalModel(const RenderSettings& settings)
    {
        for (int c = 0; c < 3; ++c) {
            mExtinction[c] = settings.medium.extinction()[c];
            mAlbedo[c] = mExtinction[c] > 0.0 ? settings.light.color[c] * settings.medium.scatter[c] / mExtinction[c] : 0.0;
            mEmitted[c] = mExtinction[c] > 0.0 ? settings.medium.emission[c] / mExtinction[c] : 0.0;
            mAmbient[c] = mExtinction[c] > 0.0 ? settings.ambient[c] * settings.medium.scatter[c] / mExtinction[c] : 0.0;
        }
    }

    /// sigma_t of channel @a c: optical depth per unit density per voxel length.
    double extinction(int c) const { return mExtinction[c]; }

    /// Optical depth of density @a density over @a voxelLengths (Eq. 7's integral of g).
    double opticalDepth(int c, double density, double voxelLengths) const
    {
        return mExtinction[c] * density * voxelLengths;
    }

    /// Source radiance per unit optical depth (the c of Eq. 7 and 10): the light's colour x
    /// scattering albedo x material colour x @a lightTransmittance, plus the ambient light
    /// scattered (ambient()), plus emission / extinction.
    double source(int c, double lightTransmittance, double materialColor) const
    {
        return mAlbedo[c] * materialColor * lightTransmittance + ambient(c, materialColor) + mEmitted[c];
    }

    /// The ambient light scattered per unit optical depth: ambient x scattering albedo x
    /// material colour. Never shadowed, so the splatter carries it with the emission.
    double ambient(int c, double materialColor) const { return mAmbient[c] * materialColor; }

    /// The scattering part of source() alone: light colour x albedo x colour x transmittance.
    double scattered(int c, double lightTransmittance, double materialColor) const
    {
        return mAlbedo[c] * materialColor * lightTransmittance;
    }

    /// The emission part of source() alone (the emission pass).
    double emitted(int c) const { return mEmitted[c]; }

    /// True if nothing scatters light: the shadow transmittance is never used.
    bool unlit() const { return mAlbedo[0] == 0.0 && mAlbedo[1] == 0.0 && mAlbedo[2] == 0.0; }

private:
    double mExtinction[3], mAlbedo[3], mEmitted[3], mAmbient[3];
};

} // namespace detail
} // namespace vdb_ewa
