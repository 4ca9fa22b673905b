/// @file render_settings.cpp
#include <vdb_ewa/render_settings.h>

#include <vdb_ewa/error.h>

#include <cmath>

namespace vdb_ewa {
namespace {

bool finite3(const Vec3d& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool nonNegative3(const Vec3d& v) { return finite3(v) && v.x >= 0.0 && v.y >= 0.0 && v.z >= 0.0; }

} // namespace

void RenderSettings::validate() const
{
    auto fail = [](const std::string& what) { throw ValueError(what); };
    if (!nonNegative3(absorb)) fail("--absorb must be finite and >= 0");
    if (!nonNegative3(scatter)) fail("--scatter must be finite and >= 0");
    if (!finite3(lightDir) || !(glm::length(lightDir) > 0.0)) fail("--light direction must be a finite non-zero vector");
    if (!nonNegative3(lightColor)) fail("--light colour must be finite and >= 0");
    if (!nonNegative3(emission)) fail("--emission must be finite and >= 0");
    for (int c = 0; c < 3; ++c) {
        if (emission[c] > 0.0 && !(absorb[c] + scatter[c] > 0.0)) {
            fail("--emission needs --absorb + --scatter > 0 in every channel that emits (the slab update divides by the optical depth)");
        }
    }
    if (!(gain >= 0.0) || !std::isfinite(gain)) fail("--gain must be finite and >= 0");
    if (!(cutoff >= 0.0 && cutoff < 1.0)) fail("--cutoff must be in [0, 1)");
    if (!(shadowStep > 0.0) || !std::isfinite(shadowStep)) fail("--shadowstep must be > 0 voxels");
    if (!(shadowResolution >= 0.25 && shadowResolution <= 16.0)) fail("--shadow-res must be in [0.25, 16] voxels");
    if (!(step >= 1e-3) || !std::isfinite(step)) fail("--step must be >= 0.001 voxels");
    if (!(kernelSigma >= 0.1 && kernelSigma <= 4.0)) fail("--kernel-sigma must be in [0.1, 4] voxels");
    if (!(surfaceSigma >= 0.1 && surfaceSigma <= 4.0)) fail("--surface-sigma must be in [0.1, 4] voxels");
    if (!(lowpass >= 0.0 && lowpass <= 100.0)) fail("--lowpass must be in [0, 100] pixels^2");
    if (antiAliasing != AntiAliasing::None && !(lowpass > 0.0)) fail("--lowpass must be > 0 unless --aa none");
    if (!(cutoffRadius >= 1.0 && cutoffRadius <= 6.0)) fail("--cutoff-radius must be in [1, 6] sigma");
    if (!(slab >= 0.05 && slab <= 1.0e4)) fail("--slab must be in [0.05, 10000] voxels");
    if (tileKernelSpacing < 1 || tileKernelSpacing > 64) fail("tile kernel spacing must be in [1, 64] voxels");
    if (!(lodPixels >= 0.0 && lodPixels <= 64.0)) fail("--lod must be in [0, 64] pixels");
    if (!std::isfinite(isovalue)) fail("--isovalue must be finite");
    if (std::isinf(iso)) fail("--iso must be finite");
    if (!(isoOpacity >= 0.0 && isoOpacity <= 1.0)) fail("--iso-opacity must be in [0, 1]");
    if (!(surfaceTolerance > 0.0 && surfaceTolerance <= 100.0)) fail("surface depth tolerance must be in (0, 100] voxels");
    if (threads < 0) fail("--threads must be >= 0");
}

RenderSettings RenderSettings::preset(Quality quality)
{
    RenderSettings s;
    switch (quality) {
    case Quality::Draft:
        s.cutoffRadius = 2.0;
        s.slab = 4.0;
        s.shadowStep = 1.0;
        s.shadowResolution = 2.0;
        s.tileKernelSpacing = 8;
        s.lodPixels = 10.0;
        break;
    case Quality::Default:
        break;
    case Quality::High:
        s.slab = 0.5;
        s.shadowStep = 0.375;
        s.shadowResolution = 0.5;
        s.tileKernelSpacing = 2;
        s.expEvaluation = ExpEvaluation::Exact;
        s.lodPixels = 0.0;
        break;
    }
    return s;
}

} // namespace vdb_ewa
