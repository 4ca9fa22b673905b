/// @file render_settings.cpp
#include <vdb_ewa/render_settings.h>

#include <vdb_ewa/error.h>

#include <cmath>
#include <string>

namespace vdb_ewa {
namespace {

bool finite3(const Vec3d& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
/// Coefficients and light colours: 1e6 per voxel length is opaque within a micro-voxel, and
/// keeps every source term, and the image, inside float's range (1e308 made Inf pixels).
constexpr double kMaxCoefficient = 1e6;
/// Point and spot lights: intensities (radiance at one world unit) and world positions.
constexpr double kMaxPointLightIntensity = 1e12, kMaxPointLightDistance = 1e12;
constexpr double kMinMemoryBudget = 64.0 * 1024 * 1024;
constexpr int kMaxOctaves = 16, kMaxPathSamples = 1 << 20, kMaxBounces = 1024;
bool coefficient3(const Vec3d& v)
{
    return finite3(v) && glm::all(glm::greaterThanEqual(v, Vec3d(0.0))) && glm::all(glm::lessThanEqual(v, Vec3d(kMaxCoefficient)));
}

} // namespace

void RenderSettings::validate() const
{
    auto fail = [](const std::string& what) { throw ValueError(what); };
    if (!coefficient3(medium.absorb)) fail("--absorb must be in [0, 1e6] per voxel length");
    if (!coefficient3(medium.scatter)) fail("--scatter must be in [0, 1e6] per voxel length");
    if (lights.size() > kMaxLights) fail("at most " + std::to_string(kMaxLights) + " --light options (each takes a light map)");
    for (const Light& light : lights) {
        if (!finite3(light.direction) || (light.direction.x == 0.0 && light.direction.y == 0.0 && light.direction.z == 0.0)) {
            fail("--light direction must be a finite non-zero vector");
        }
        if (!coefficient3(light.color)) fail("--light colour must be in [0, 1e6]");
    }
    if (!coefficient3(medium.emission)) fail("--emission must be in [0, 1e6] per voxel length");
    if (!coefficient3(ambient)) fail("--ambient must be in [0, 1e6]");
    if (pointLights.size() > kMaxLights) fail("at most " + std::to_string(kMaxLights) + " --point-light and --spot-light options (each takes a light map)");
    for (const PointLight& light : pointLights) {
        const char* name = light.spotAngle > 0.0 ? "--spot-light" : "--point-light";
        const auto within = [](const Vec3d& v, double most) { return finite3(v) && glm::all(glm::lessThanEqual(glm::abs(v), Vec3d(most))); };
        if (!within(light.position, kMaxPointLightDistance)) fail(std::string(name) + " position must be finite, each coordinate within 1e12");
        if (!within(light.color, kMaxPointLightIntensity) || !glm::all(glm::greaterThanEqual(light.color, Vec3d(0.0)))) {
            fail(std::string(name) + " intensity R,G,B must be in [0, 1e12]");
        }
        if (!(light.radius >= 0.0 && light.radius <= kMaxPointLightDistance)) fail(std::string(name) + " radius must be in [0, 1e12] world units");
        if (!(light.spotAngle >= 0.0 && light.spotAngle <= 180.0)) fail("--spot-light cone angle must be in (0, 180] degrees");
        if (light.spotAngle > 0.0) {
            const Vec3d axis = light.spotTarget - light.position;
            if (!within(light.spotTarget, kMaxPointLightDistance) || !(glm::length(axis) > 0.0)) {
                fail("--spot-light target must be finite and away from the light's position");
            }
            if (!(light.spotBlend >= 0.0 && light.spotBlend <= 1.0)) fail("--spot-light blend must be in [0, 1]");
        }
    }
    if (!coefficient3(gridEmission.color)) fail("--emission-color must be in [0, 1e6]");
    if (!(gridEmission.intensity >= 0.0 && gridEmission.intensity <= kMaxCoefficient)) fail("--emission-intensity must be in [0, 1e6]");
    if (!(gridEmission.blackbodyIntensity >= 0.0 && gridEmission.blackbodyIntensity <= kMaxCoefficient)) {
        fail("--blackbody-intensity must be in [0, 1e6]");
    }
    if (!(std::abs(gridEmission.kelvinScale) <= 1e6) || !(std::abs(gridEmission.kelvinOffset) <= 1e6)) {
        fail("--temperature-scale and --temperature-offset must be finite and within 1e6 Kelvin");
    }
    for (int c = 0; c < 3; ++c) {
        if (!finite3(gridEmission.rec709ToWorking[c]) || !(glm::length(gridEmission.rec709ToWorking[c]) <= kMaxCoefficient)) {
            fail("the blackbody's colour matrix (GridEmission::rec709ToWorking) must be finite");
        }
        if (!finite3(inputToWorking[c]) || !(glm::length(inputToWorking[c]) <= kMaxCoefficient)) {
            fail("the input colours' matrix (RenderSettings::inputToWorking) must be finite");
        }
    }
    for (int c = 0; c < 3; ++c) {
        if (medium.emission[c] > 0.0 && !(medium.absorb[c] + medium.scatter[c] > 0.0)) {
            fail("--emission needs --absorb + --scatter > 0 in every channel that emits (the slab update divides by the optical depth)");
        }
    }
    if (!(scattering.anisotropy > -1.0 && scattering.anisotropy < 1.0)) fail("--anisotropy must be in (-1, 1)");
    if (!(scattering.octaves >= 1 && scattering.octaves <= kMaxOctaves)) fail("--multiple-scattering must be in [1, " + std::to_string(kMaxOctaves) + "] octaves");
    if (!(scattering.octaveScatter >= 0.0 && scattering.octaveScatter <= 1.0)) fail("--octave-scatter must be in [0, 1]");
    if (!(scattering.octaveExtinction >= 0.0 && scattering.octaveExtinction <= 1.0)) fail("--octave-extinction must be in [0, 1]");
    if (!(scattering.octaveAnisotropy >= 0.0 && scattering.octaveAnisotropy <= 1.0)) fail("--octave-anisotropy must be in [0, 1]");
    if (!(pathSamples >= 1 && pathSamples <= kMaxPathSamples)) fail("--samples must be in [1, " + std::to_string(kMaxPathSamples) + "] paths per pixel");
    if (!(bounces >= 0 && bounces <= kMaxBounces)) fail("--bounces must be in [0, " + std::to_string(kMaxBounces) + "]");
    if (!(shadow.gain >= 0.0) || !std::isfinite(shadow.gain)) fail("--gain must be finite and >= 0");
    if (!(cutoff >= 0.0 && cutoff < 1.0)) fail("--cutoff must be in [0, 1)");
    if (!(shadow.step >= 1e-3) || !std::isfinite(shadow.step)) fail("--shadowstep must be finite and >= 0.001 voxels");
    if (!(shadow.resolution >= 0.25 && shadow.resolution <= 16.0)) fail("--shadow-res must be in [0.25, 16] voxels");
    if (!(step >= 1e-3) || !std::isfinite(step)) fail("--step must be >= 0.001 voxels");
    if (!(blurSamples >= 1 && blurSamples <= 4096)) fail("--blur-samples must be in [1, 4096]");
    if (!(pixelSamples >= 1 && pixelSamples <= 4096)) fail("--pixel-samples must be in [1, 4096]");
    if (!(splat.supersample >= 1 && splat.supersample <= kMaxSupersample)) fail("--supersample must be in [1, " + std::to_string(kMaxSupersample) + "]");
    if (!(splat.supersampleSpan >= 0.5 && splat.supersampleSpan <= 16.0)) fail("--supersample-span must be in [0.5, 16] pixels");
    if (!(std::abs(motionBlur.velocityScale) <= 1e6)) fail("--velocity-scale must be finite and within 1e6");
    if (!(motionBlur.fps >= 1e-3 && motionBlur.fps <= 1e6)) fail("--fps must be in [0.001, 1e6] frames per second");
    if (!(std::abs(motionBlur.shutterOpen) <= 1e3 && std::abs(motionBlur.shutterClose) <= 1e3)) fail("--shutter times must be finite and within 1000 frames of the frame");
    if (!(motionBlur.shutterClose >= motionBlur.shutterOpen)) fail("--shutter: the close time must not come before the open time");
    if (!(motionBlur.samples >= 1 && motionBlur.samples <= 1024)) fail("--motion-samples must be in [1, 1024]");
    if (!(motionBlur.layers >= 1 && motionBlur.layers <= kMaxShutterLayers)) fail("--motion-layers must be in [1, " + std::to_string(kMaxShutterLayers) + "]");
    if (!(motionBlur.splitSigmas >= 0.5 && motionBlur.splitSigmas <= 64.0)) fail("--motion-split must be in [0.5, 64] standard deviations");
    if (!(lensSamples >= 1 && lensSamples <= 1024)) fail("--lens-samples must be in [1, 1024]");
    if (!(splat.kernelSigma >= 0.1 && splat.kernelSigma <= 4.0)) fail("--kernel-sigma must be in [0.1, 4] voxels");
    if (!(surface.sigma >= 0.1 && surface.sigma <= 4.0)) fail("--surface-sigma must be in [0.1, 4] voxels");
    if (!(splat.lowpass >= 0.0 && splat.lowpass <= 100.0)) fail("--lowpass must be in [0, 100] pixels^2");
    if (splat.antiAliasing != AntiAliasing::None && !(splat.lowpass > 0.0)) fail("--lowpass must be > 0 unless --aa none");
    if (!(splat.cutoffRadius >= 1.0 && splat.cutoffRadius <= 6.0)) fail("--cutoff-radius must be in [1, 6] sigma");
    if (!(splat.slab >= 0.05 && splat.slab <= 1.0e4)) fail("--slab must be in [0.05, 10000] voxels");
    if (splat.tileKernelSpacing < 1 || splat.tileKernelSpacing > 64) fail("tile kernel spacing must be in [1, 64] voxels");
    if (splat.refine < 1 || splat.refine > 4) fail("--refine must be in [1, 4]");
    if (splat.refineEmission < 1 || splat.refineEmission > 4) fail("--refine-emission must be in [1, 4]");
    if (!(splat.lodPixels >= 0.0 && splat.lodPixels <= 64.0)) fail("--lod must be in [0, 64] pixels");
    if (!(splat.lodError >= 0.0 && splat.lodError <= 1.0)) fail("--lod-error must be in [0, 1] (a difference of transmittance)");
    if (splat.pixelSize < 1 || splat.pixelSize > 16) fail("--pixel-size must be in [1, 16] pixels");
    if (!(splat.pixelSizeBlur > 0.0 && splat.pixelSizeBlur <= 1.0)) fail("--pixel-size-blur must be in (0, 1] (a share of the kernel's variance)");
    if (!(splat.imageLod == 0.0 || (splat.imageLod >= 1.0 && splat.imageLod <= 64.0))) fail("--image-lod must be off (0) or in [1, 64] samples");
    if (!std::isfinite(surface.isovalue)) fail("--isovalue must be finite");
    if (std::isinf(surface.iso)) fail("--iso must be finite");
    if (!(surface.isoOpacity >= 0.0 && surface.isoOpacity <= 1.0)) fail("--iso-opacity must be in [0, 1]");
    if (!(surface.tolerance > 0.0 && surface.tolerance <= 100.0)) fail("surface depth tolerance must be in (0, 100] voxels");
    if (!(threads >= 0 && threads <= kMaxThreads)) fail("--threads must be in [0, " + std::to_string(kMaxThreads) + "] (0: all cores)");
    if (!(maxMemory == 0.0 || (maxMemory >= kMinMemoryBudget && maxMemory <= 1.0e18))) fail("--max-memory must be 0 (3/4 of the physical memory) or in [64M, 1e18] bytes");
}

RenderSettings RenderSettings::preset(Quality quality)
{
    RenderSettings s;
    switch (quality) {
    case Quality::Draft:
        s.splat.cutoffRadius = 2.0;
        s.splat.slab = 4.0;
        s.shadow.step = 1.0;
        s.shadow.resolution = 2.0;
        s.splat.tileKernelSpacing = 8;
        s.splat.lodPixels = 10.0;
        s.splat.lodError = 0.25;
        s.splat.taper = true;
        s.splat.refineEmission = 1;
        s.motionBlur.samples = 1;
        s.motionBlur.layers = 1;
        s.motionBlur.splitSigmas = 4.0;
        s.motionBlur.lightFollows = false;
        s.lensSamples = 1;
        s.splat.supersample = 16;
        s.splat.supersampleSpan = 1.0;
        // No image levels: its larger pixels make a draft coarse, and on top of them the levels
        // (--image-lod 1) saved no time, added pops and memory, and cost 0.2-0.7 dB
        // (docs/performance.md#image-space-level-of-detail).
        s.splat.imageLod = 0.0;
        s.splat.pixelSizeBlur = 1.0;
        s.splat.prefilter = false;
        break;
    case Quality::Default:
        break;
    case Quality::High:
        s.splat.slab = 0.5;
        s.shadow.step = 0.375;
        s.shadow.resolution = 0.5;
        s.splat.tileKernelSpacing = 2;
        s.splat.expEvaluation = ExpEvaluation::Exact;
        s.splat.lodPixels = 0.0;
        s.splat.imageLod = 0.0;
        s.splat.imageLodComposite = false;
        s.splat.pixelSize = 1;
        s.splat.refineEmission = 4;
        s.motionBlur.samples = 4;
        s.motionBlur.layers = 1;
        s.lensSamples = 8;
        break;
    case Quality::Final: // high, with refined kernels where voxels span 2 pixels or more
        s = preset(Quality::High);
        s.splat.slab = 0.25;
        s.splat.refine = 2;
        s.motionBlur.samples = 8;
        s.lensSamples = 16;
        break;
    }
    return s;
}

} // namespace vdb_ewa
