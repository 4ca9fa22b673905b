/// @file render_options.cpp
#include "render_options.h"

#include "camera_file_option.h"
#include "frame_sequence.h"
#include "granted_resources.h"
#include "option_values.h"

#include <cmath>
#include <exception>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include <unistd.h>

namespace vdb_ewa::cli {
namespace {

const Choices<Quality> kQualities = {{"draft", Quality::Draft}, {"default", Quality::Default}, {"high", Quality::High}, {"final", Quality::Final}};
const Choices<Method> kMethods = {{"splat", Method::Splat}, {"raymarch", Method::RayMarch}, {"raymarch-gaussian", Method::RayMarchGaussian},
    {"pathtrace", Method::PathTrace}};
const Choices<AntiAliasing> kAntiAliasing = {{"ewa", AntiAliasing::Ewa}, {"floor", AntiAliasing::Floor}, {"swan", AntiAliasing::Swan}, {"none", AntiAliasing::None}};
const Choices<ExpEvaluation> kExpEvaluations = {
    {"incremental", ExpEvaluation::Incremental}, {"exact", ExpEvaluation::Exact}, {"table", ExpEvaluation::Table}};
const Choices<bool> kOnOff = {{"on", true}, {"off", false}};
const Choices<bool> kPrecisions = {{"double", true}, {"float", false}}; // doublePrecision
const Choices<VelocityUnit> kVelocityUnits = {{"second", VelocityUnit::Second}, {"frame", VelocityUnit::Frame}};
const Choices<bool> kMotionLights = {{"follow", true}, {"still", false}};
const Choices<SurfaceShader> kShaders = {{"diffuse", SurfaceShader::Diffuse}, {"matte", SurfaceShader::Matte},
    {"normal", SurfaceShader::Normal}, {"position", SurfaceShader::Position}};

/// @a camera's settings with its orientation named (for the exact record): the default
/// target made an explicit --lookat, looking down -z made --rotate 0,0,0, and a replaced
/// --up made the axis Camera used.
CameraSettings explicitCamera(const Camera& camera, const Vec3d& defaultTarget)
{
    CameraSettings s = camera.settings();
    if (s.rotate || s.lookAt) return s;
    if (camera.looksDownZByDefault()) {
        s.rotate = Vec3d(0.0);
        return s;
    }
    s.lookAt = defaultTarget;
    if (camera.upReplacedByDefault()) {
        const Mat3d& r = camera.cameraFromWorld(); // rows: right, down, forward
        const Vec3d back = -Vec3d(r[0][2], r[1][2], r[2][2]);
        s.up = std::abs(back.z) < 0.9 ? Vec3d(0, 0, back.y > 0.0 ? 1.0 : -1.0) : Vec3d(1, 0, 0);
    }
    return s;
}

std::string hostName()
{
    char name[256] = {};
    return gethostname(name, sizeof name - 1) == 0 ? std::string(name) : std::string("unknown");
}

} // namespace

void RenderOptions::add(CLI::App* app)
{
    mApp = app;
    const RenderSettings rs;
    const CameraSettings cs;
    mApp->add_option("--name,--density-grid", mName,
        "grid to render, as the density of a fog volume or a level set; --density-grid is the same option under the "
        "name a pyro cache's user looks for (default: the first scalar float or double grid, as vdb_render)");
    // Camera (vdb_render semantics).
    mApp->add_option("--camera-file", mCameraFile,
        "take the camera from a file: an .exr rendered by vdb_ewa (the same camera exactly) or by another renderer "
        "(its worldToCamera), or a .json of camera options or a worldToCamera matrix (docs/output.md); the camera "
        "options given here override its values");
    mApp->add_option("--res", mRes, "image size in pixels, WxH, each in [1, 65536] and at most 2^27 pixels in all (16384x8192) (default: 1920x1080)");
    mApp->add_option("-t,--translate", mTranslate, "camera position X,Y,Z in world units (default: 0,0,0)");
    mApp->add_option("-r,--rotate", mRotate,
        "camera rotation X,Y,Z in degrees, applied about x, then y, then z (default: look at the "
        "centre of the grid's active voxels)");
    mApp->add_option("--lookat", mLookAt, "aim the camera at the world point X,Y,Z");
    mApp->add_option("--up", mUp, "world vector that points up after --lookat (default: 0,1,0)");
    mApp->add_option("--camera", mCamera, "camera type: persp[ective] or ortho[graphic] (default: perspective)");
    mApp->add_option("--fov", mFov, "horizontal field of view in degrees, in (0, 179) (default: " + fmt(cs.fieldOfView()) + ", from --focal and --aperture)");
    mApp->add_option("--focal", mFocal, "perspective focal length in mm, > 0 (default: " + fmt(cs.focal) + ")");
    mApp->add_option("--aperture", mAperture, "perspective frame width in mm, > 0 (default: " + fmt(cs.aperture) + ")");
    mApp->add_option("--frame", mFrame, "orthographic frame width in world units, > 0 (default: " + fmt(cs.frame) + ")");
    mApp->add_option("--fstop", mFstop,
        "depth of field: the thin lens's f-number, in [0, 1e6]; the lens is --focal / fstop wide, world units taken as metres "
        "(Houdini's and Blender's); 0: a pinhole, no depth of field; perspective cameras (default: 0)");
    mApp->add_option("--focus-distance", mFocusDistance,
        "depth of field: the depth in focus, world units along the view axis, > 0 (default: the depth of the point looked at, "
        "--lookat or the grid's centre)");
    mApp->add_option("--near", mNear, "near plane depth in world units, > 0 (default: " + fmt(cs.near) + ")");
    mApp->add_option("--far", mFar, "far plane depth in world units, > --near; inf: none (default: " + fmt(cs.far) + ")");
    // Optical model (vdb_render's dense-volume model).
    mApp->add_option("--absorb", mAbsorb, "absorption R,G,B per unit density per voxel length, each in [0, 1e6] (default: " + fmt3(rs.medium.absorb) + ")");
    mApp->add_option("--scatter", mScatter, "scattering R,G,B per unit density per voxel length, each in [0, 1e6] (default: " + fmt3(rs.medium.scatter) + ")");
    mApp->add_option("--light", mLights,
            "directional light: direction towards it X,Y,Z (any non-zero length)[,R,G,B] with optional colour, each in [0, 1e6]; "
            "repeat for more lights (at most " + std::to_string(kMaxLights) + "), each with its own shadows; their light adds (default: one, " +
                fmt3(rs.lights.front().direction) + "," + fmt3(rs.lights.front().color) + ")")
        ->allow_extra_args(false);
    mApp->add_option("--point-light", mPointLights,
            "point light at world X,Y,Z (each within 1e12)[,R,G,B]: intensity R,G,B (the radiance it gives at one world unit; falls off as 1/(distance^2 + radius^2)), "
            "each in [0, 1e12]; inside the volume too; shadowed through a light map of rays from it; repeat for more (at most " +
                std::to_string(kMaxLights) + "); fog volumes and --iso surfaces (default: none; intensity 1,1,1)")
        ->allow_extra_args(false);
    mApp->add_option("--spot-light", mSpotLights,
            "spot light at world X,Y,Z aimed at TX,TY,TZ, full cone ANGLE in degrees in (0, 180][,BLEND,R,G,B]: BLEND the fraction "
            "of the cone's edge that fades, in [0, 1] (default 0.15, Blender's), intensity as --point-light; repeat for more "
            "(default: none)")
        ->allow_extra_args(false);
    mApp->add_option("--point-light-radius", mPointLightRadius,
        "world units: nearer than this (and than half a voxel) a point or spot light grows no brighter, in [0, 1e12] (default: 0)");
    mApp->add_option("--emission", mEmission,
        "self-emission R,G,B per unit density per voxel length, each in [0, 1e6], added to the scattered light (default: " +
            fmt3(rs.medium.emission) + ")");
    mApp->add_option("--ambient", mAmbient,
        "constant ambient (sky) light R,G,B, never shadowed, scattered like --light: a fill for fog volumes; each in "
        "[0, 1e6], in --input-space (default: 0,0,0)");
    mApp->add_option("--environment", mEnvironment,
        "latitude-longitude environment image (.exr, .hdr; OpenEXR's and USD's orientation: +Y up, its centre facing +Z), RGB radiance in --input-space: "
        "a low-order, shadowed fill, added to --light as --environment-lights directional lights (default: none)");
    mApp->add_option("--environment-lights", mEnvironmentLights,
        "lights the environment becomes, each from the part of the sphere nearest its direction, in [1, " +
            std::to_string(kMaxLights) + "] (default: 16)");
    mApp->add_option("--environment-intensity", mEnvironmentIntensity, "multiplies the environment's radiance, >= 0 (default: 1)");
    mApp->add_option("--anisotropy", mAnisotropy,
        "Henyey-Greenstein phase function's g for every light but --ambient, in (-1, 1): > 0 scatters forwards, so a back-lit "
        "edge glows (water droplets 0.6-0.9), 0 isotropic, vdb_render's (docs/lighting.md#scattering) (default: 0)");
    mApp->add_option("--multiple-scattering", mOctaves,
        "octaves of multiple scattering, in [1, 16]: octave i scatters each light again with --octave-scatter^i of the scattering, "
        "--octave-extinction^i of its optical depth and --octave-anisotropy^i of the anisotropy, from the same light maps: the "
        "soft, bright body light scattered many times gives a cloud; 1 single scattering, vdb_render's (docs/lighting.md#multiple-scattering) (default: 1)");
    mApp->add_option("--octave-scatter", mOctaveScatter,
        "each octave's scattering relative to the one before, in [0, 1] (default: " + fmt(rs.scattering.octaveScatter) + ")");
    mApp->add_option("--octave-extinction", mOctaveExtinction,
        "each octave's light optical depth relative to the one before, in [0, 1] (default: " + fmt(rs.scattering.octaveExtinction) + ")");
    mApp->add_option("--octave-anisotropy", mOctaveAnisotropy,
        "each octave's anisotropy relative to the one before, in [0, 1] (default: " + fmt(rs.scattering.octaveAnisotropy) + ")");
    mApp->add_option("--bounces", mBounces,
        "--method pathtrace: scattering events after the first a path may have (Cycles' Volume Bounces), in [0, 1024]; 0 single "
        "scattering (default: " + std::to_string(rs.bounces) + ")");
    mApp->add_option("--gain", mGain, "shadow-ray extinction falls as 1/(1 + gain * distance in voxels), finite and >= 0 (default: " + fmt(rs.shadow.gain) + ")");
    mApp->add_option("--cutoff", mCutoff,
        "density cutoff, and rays stop where |transmittance RGB|^2 < cutoff; range [0, 1) (default: " + fmt(rs.cutoff) + ")");
    mApp->add_option("--shadowstep", mShadowStep, "shadow-ray step in voxels, >= 0.001; the light map's budget may raise it (docs/numerics.md) (default: " + fmt(rs.shadow.step) + ")");
    mApp->add_option("--shadow-res", mShadowRes, "light map: shadow rays every N voxels across the light, interpolated in between; range [0.25, 16] (default: " + fmt(rs.shadow.resolution) + ")");
    mApp->add_option("--step", mStep, "primary-ray step in voxels for --method raymarch, >= 0.001 (default: " + fmt(rs.step) + "); the splatter has no primary rays and ignores it");
    mApp->add_option("--method", mMethod, "splat (EWA volume splatting), raymarch (the reference: ray-marches the trilinear field with a shadow ray per sample, as vdb_render; slow) or raymarch-gaussian (diagnostic: ray-marches the splatter's own Gaussian reconstruction and per-kernel shadows) or pathtrace (the truth of "
        "multiple scattering: --samples paths per pixel through the trilinear field, each scattering up to --bounces more times, physical shadows "
        "(--gain 0); slowest) (default: splat)");
    // EWA splatting.
    mApp->add_option("--kernel-sigma", mKernelSigma, "reconstruction kernel std. deviation in voxels, range [0.1, 4] (default: " + fmt(rs.splat.kernelSigma) + ")");
    mApp->add_option("--surface-sigma", mSurfaceSigma, "level sets and --iso: surface kernel std. deviation along the surface in voxels, range [0.1, 4] (default: " + fmt(rs.surface.sigma) + ")");
    mApp->add_option("--lowpass", mLowpass, "screen-space low-pass filter variance in pixels^2, range [0, 100], > 0 unless --aa none (default: " + fmt(rs.splat.lowpass) + ")");
    mApp->add_option("--aa", mAa, "anti-aliasing: floor (each footprint axis at least --lowpass wide), ewa (resampling filter, Eq. 33: always adds --lowpass), swan (uniform scaling) or none (default: floor)");
    mApp->add_option("--cutoff-radius", mCutoffRadius, "footprint cut-off radius in std. deviations, range [1, 6] (default: " + fmt(rs.splat.cutoffRadius) + ")");
    mApp->add_option("--slab", mSlab, "image-aligned slab thickness in voxel lengths, range [0.05, 10000]; no thinner than --lod/16 pixel widths (--supersample-span/16 at --lod 0) at the nearest active voxel (default: " + fmt(rs.splat.slab) + ")");
    mApp->add_option("--quality", mQuality,
        "preset of the speed/accuracy knobs: draft, default, high or final (refined kernels); explicit options override it "
        "(values in docs/performance.md) (default: default)");
    mApp->add_option("--exp", mExp, "footprint exp(-r/2): incremental (forward differencing), exact or table (default: incremental)");
    mApp->add_option("--prefilter", mPrefilter, "on: quasi-interpolating kernel weights (the Gaussian sum keeps the trilinear field's sharpness; negative halo kernels at its faces); off: each kernel weighs its voxel's value, softer and cheaper (default: on, draft off)");
    mApp->add_option("--renormalize", mRenormalize, "on: divide footprints by the mass kept inside --cutoff-radius; off: keep the truncated mass (default: on)");
    mApp->add_option("--taper", mTaper, "on: footprints are the Gaussian less its value at --cutoff-radius, falling to 0 at their edge (no step to flicker as they move); off: truncated (default: off, draft on)");
    mApp->add_option("--precision", mPrecision, "world-to-camera transform and covariances in double or float (default: double)");
    mApp->add_option("--tile-spacing", mTileSpacing, "largest kernel spacing in voxels for active tiles seen large, 1 to voxelise them; seen small a tile's spacing follows --lod pixels (--supersample-span at --lod 0) up to the tile's own size, between two spacings continuously with distance (docs/equations.md#active-tiles-seen-small) (default: 4, draft 8, high 2)");
    mApp->add_option("--refine", mRefine, "where voxels span N pixels or more, their kernels on a lattice N times finer: the trilinear field sampled every 1/N voxel (emission and temperature grids too), kernels N times narrower, N^3 as many; range [1, 4], 1 = off (default: " + std::to_string(rs.splat.refine) + ")");
    mApp->add_option("--refine-emission", mRefineEmission, "emission and temperature grids where their light does not go as the density (light over density changes several-fold between neighbouring voxels) in optically thick density: the light sampled every 1/n voxel, n up to N as the voxels span n pixels or more (2 at least); --refine refines the emitters too; range [1, 4], 1 = off (default: " + std::to_string(rs.splat.refineEmission) + "; draft 1, high and final 4)");
    mApp->add_option("--lod", mLod, "level of detail, pixels in [0, 64]: fog volumes: blocks of 2, 4 or 8 voxels a side become one kernel where the block projects to at most this many pixels, each voxel shared between two block sizes continuously with distance (no popping); level sets: one surface kernel a 2^3 or 4^3 block of voxels (for each sheet through it) where the block projects to at most a quarter as many; active tiles seen small: their kernels this many pixels apart (--tile-spacing); 0 = off (tiles: --supersample-span pixels) (default: " + fmt(rs.splat.lodPixels) + ")");
    mApp->add_option("--lod-error", mLodError, "level of detail, fog volumes: a block wider than a pixel merges only where its values are smooth: the transmittance through any depth of it differs by at most this much between its columns; range [0, 1], 1 = by screen size alone (default: " + fmt(rs.splat.lodError) + ", draft 0.25)");
    mApp->add_option("--image-lod", mImageLod,
        "image-space level of detail, samples, off or in [1, 64]: fog volumes: a footprint is accumulated at every 2nd, 4th or 8th "
        "pixel of its screen tile, the coarsest whose spacing its narrowest standard deviation spans at least this many times, and "
        "interpolated bilinearly onto the pixels when its slab is composited (at most 1/(4 n^2) of a footprint's peak off; "
        "docs/equations.md#image-space-level-of-detail); wide footprints (voxels seen large, a camera inside the volume) cost a "
        "third to a 16th of the samples, and with --image-lod-composite of the composites (docs/performance.md#image-space-level-of-detail); "
        "off = every footprint at every pixel (default: " + imageLodName(rs.splat.imageLod) + "; draft, high and final off)");
    mApp->add_option("--image-lod-composite", mImageLodComposite,
        "on: with --image-lod, a screen tile whose footprints so far all lie at a coarser sample grid is also lit and composited "
        "there (the light lookups, the exact update and termination at every 2nd, 4th or 8th pixel), and its colour, "
        "transmittance and passes interpolated bilinearly onto the pixels when it is finished or a narrower footprint arrives "
        "(docs/equations.md#compositing-at-a-coarser-level); frames with deep output, --iso surfaces or shutter layers composite "
        "at every pixel; off: every tile composited at its pixels (default: on, high and final off; no effect while --image-lod is off)");
    mApp->add_option("--pixel-size", mPixelSize,
        "larger pixels, whole pixels in [1, 16]: a fog volume whose voxels look large is splatted at one sample an n x n block "
        "of pixels and interpolated bilinearly back onto the pixels (footprints filtered at the larger pixel: blurrier, never "
        "aliased; Z from the nearest larger pixel), n the largest up to this at which the median voxel in view still spans "
        "--supersample-span samples and the larger pixel's filter adds at most --pixel-size-blur of the kernel's variance, "
        "the next size's frame fading in near it (no jump as a camera moves; docs/equations.md#larger-pixels); volumes seen "
        "smaller, level sets, --iso surfaces and deep images keep every pixel; 1 = off "
        "(default: " + std::to_string(rs.splat.pixelSize) + ", draft 4, high and final 1)");
    mApp->add_option("--pixel-size-blur", mPixelSizeBlur,
        "with --pixel-size: the variance the larger pixel's filter (its low-pass and the bilinear tent) may add to a voxel's "
        "footprint, as a share of the kernel's own, in (0, 1]: n <= --kernel-sigma x the voxel's pixels x sqrt(this / "
        "(--lowpass + 1/6)); the finest detail at most sqrt(1 + this) wider: at the defaults 3 % (2x2 pixels a sample from "
        "voxels of 17 pixels, 4x4 from 35), draft 1: 41 % (from 4.3 and 8.6 pixels) (default: " + fmt(rs.splat.pixelSizeBlur) + ", draft 1)");
    mApp->add_option("--supersample", mSupersample,
        "fog volumes: where the voxels look smaller than --supersample-span pixels, the pixels the volume covers are composited "
        "in S x S sub-pixels and averaged (a box filter, as a camera averages a pixel; one footprint a pixel wide averages optical "
        "depth instead, which renders small volumes too opaque and too bright: docs/equations.md#sub-pixel-samples), S = "
        "ceil(span / the median voxel's pixels, active tiles counting as their voxels) up to this; at most 16 images' sub-pixels (and half "
        "of --max-memory), and 32 kernels a pixel of tiles larger than a leaf node (their lattices follow the sub-pixels); up to S^2 "
        "times the compositing where it acts; range [1, " + std::to_string(kMaxSupersample) + "], 1 = off (default: " +
        std::to_string(rs.splat.supersample) + "; draft 16)");
    mApp->add_option("--supersample-span", mSupersampleSpan,
        "fog volumes: sub-pixels a voxel should span, in [0.5, 16]; larger converges further to a camera's average where voxels "
        "are small, at more sub-pixels; at 2 images have converged as far as sub-pixels take them (default: " + fmt(rs.splat.supersampleSpan) + "; draft 1)");
    // Fog volumes with an iso-surface.
    mApp->add_option("--iso", mIso,
        "fog volumes: also render the iso-surface density = VALUE with flattened surface kernels, lit by "
        "--light and composited with the volume; finite, nan: off (default: off)");
    mApp->add_option("--iso-opacity", mIsoOpacity, "opacity of the --iso surface, 0..1 (default: 1)");
    // Level sets (vdb_render's level-set options).
    mApp->add_option("--isovalue", mIsovalue, "level sets: iso-surface to render, in world units, finite (default: " + fmt(rs.surface.isovalue) + ")");
    mApp->add_option("--shader", mShader,
        "level sets: diffuse (|N.ray|, a light at the camera), matte (white), normal ((N+1)/2) or position "
        "(world position in the active bounding box) (default: diffuse)");
    mApp->add_option("--color", mColor,
        "name of a vec3s grid in the input file with material colours, sampled trilinearly: level sets multiply "
        "the shader by it, fog volumes the scattering albedo (and the --iso surface's colour) (default: white)");
    // Emission from grids (pyro caches).
    const GridEmission ge;
    mApp->add_option("--emission-grid", mEmissionGrid,
        "name of a float grid in the input file that emits light wherever it is, whatever the density (a pyro cache's "
        "flame): radiance --emission-color x --emission-intensity x value per voxel length (default: none)");
    mApp->add_option("--emission-color", mEmissionColor,
        "colour R,G,B of --emission-grid, each in [0, 1e6], in --input-space (default: " + fmt3(ge.color) + ")");
    mApp->add_option("--emission-intensity", mEmissionIntensity,
        "multiplies --emission-color, in [0, 1e6] (default: " + fmt(ge.intensity) + ")");
    mApp->add_option("--temperature", mTemperatureGrid,
        "name of a float grid in the input file whose values are temperatures: blackbody emission of Planck's law "
        "(CIE 1931 colour, luminance --blackbody-intensity x 1e-6 sigma T^4 / pi per voxel length, Blender's Principled "
        "Volume) wherever it is, whatever the density (default: none)");
    mApp->add_option("--temperature-scale", mKelvinScale,
        "Kelvin per unit of --temperature's values: Kelvin = value x scale + offset (Blender: the node's Temperature; "
        "Houdini: T1 - T0), within 1e6 (default: " + fmt(ge.kelvinScale) + ")");
    mApp->add_option("--temperature-offset", mKelvinOffset,
        "Kelvin at value 0 (Houdini: T0), within 1e6 (default: " + fmt(ge.kelvinOffset) + ")");
    mApp->add_option("--blackbody-intensity", mBlackbodyIntensity,
        "multiplies the blackbody's radiance, in [0, 1e6]; 1 is physically based (default: " + fmt(ge.blackbodyIntensity) + ")");
    // Several volumes in one sweep.
    mApp->add_option("--add-volume", mAddVolumes,
            "another fog volume in the same frame, FILE[:GRID] (GRID: the first float grid by default): its density is "
            "added to the input's on the input's voxels (resampled trilinearly where its transform differs: name the finest "
            "volume first), so volumes that interpenetrate hide and shadow each other in one sweep; same optical model; with "
            "--velocity-grid, each moves with its own velocity grid of that name (none: it stands still); repeat for more (default: none)")
        ->allow_extra_args(false);
    mApp->add_option("--add-volume-transform", mAddVolumeTransforms,
            "the object-to-world transform of the --add-volume of the same rank (the first for the first): 16 numbers, "
            "a 4x4 matrix row by row, or its first 12 (the last row 0,0,0,1); column vectors, world = M (x, y, z, 1), "
            "after the file's own index-to-world map, as a DCC object's transform moves its volume (its velocities turn "
            "with it); finite, affine and invertible; one for every --add-volume, or none (default: none, the identity)")
        ->allow_extra_args(false);
    mApp->add_option("--add-volume-material", mAddVolumeMaterials,
            "the optical model of the --add-volume of the same rank, its own where they interpenetrate: KEY=VALUE words, "
            "absorb=R,G,B scatter=R,G,B emission=R,G,B (per unit of its density per voxel length, as --absorb, --scatter, "
            "--emission; one number: grey; what it does not name is the input's) and color=GRID emission-grid=GRID "
            "temperature=GRID (its file's grids, as --color, --emission-grid, --temperature); 'same': the input's model, "
            "colour and emission grids; one for every --add-volume, or none (default: none, every volume takes the input's)")
        ->allow_extra_args(false);
    // Motion blur (fog volumes).
    const MotionBlur mb;
    mApp->add_option("--velocity-grid", mVelocityGrid,
        "motion blur: name of the velocity grid in the input file, a vec3s or vec3d grid (Houdini's v or vel) or the float grids "
        "NAME.x, NAME.y, NAME.z (Blender's); each kernel moves linearly over the shutter with the velocity at its centre; "
        "naming one turns motion blur on; each --add-volume file's grid of that name moves that volume (default: none)");
    mApp->add_option("--velocity-scale", mVelocityScale, "motion blur: multiplies the velocities, within 1e6 (default: " + fmt(mb.velocityScale) + ")");
    mApp->add_option("--velocity-unit", mVelocityUnit, "motion blur: second (world units per second, Houdini's and Blender's) or frame (world units per frame) (default: second)");
    mApp->add_option("--fps", mFps, "motion blur: frames per second, for --velocity-unit second, in [0.001, 1e6] (default: " + fmt(mb.fps) + ")");
    mApp->add_option("--shutter", mShutter,
        "motion blur: shutter OPEN,CLOSE in frames around the frame's time, each within 1000, CLOSE >= OPEN (default: " +
            fmt(mb.shutterOpen) + "," + fmt(mb.shutterClose) + ", a 180-degree shutter centred on the frame)");
    mApp->add_option("--motion-samples", mMotionSamples,
        "motion blur: sub-frames over the shutter, each blurred over its part of it, averaged; widened kernels blur optical "
        "depth where a camera averages images, so opaque edges need more to converge (docs/equations.md#motion-blur); "
        "about N times the time; range [1, 1024] (default: " + std::to_string(mb.samples) + "; draft 1, high 4, final 8)");
    mApp->add_option("--motion-split", mMotionSplit,
        "motion blur: a kernel whose path over its sub-frame is longer on the screen than this many of its standard "
        "deviations is split into sub-kernels of at most that length; smaller keeps the blur's box shape closer (a single "
        "kernel's blur within 1.2 % of its peak at 2, 4.6 % at 3, 11 % at 4) at the cost of more kernels; in [0.5, 64] "
        "(default: " + fmt(mb.splitSigmas) + "; draft 4)");
    mApp->add_option("--motion-layers", mMotionLayers,
        "motion blur: transmittances each pixel keeps over each sub-frame, one per equal part of its shutter; a split "
        "kernel's pieces darken only their parts, so an opaque edge moving across a pixel covers it part of the shutter, "
        "as sub-frames would, in one sweep, each layer lit where its own material came from (--motion-light follow) "
        "(docs/equations.md#shutter-layers); 1: off; range [1, " +
            std::to_string(kMaxShutterLayers) + "] (default: " + std::to_string(mb.layers) + "; draft 1, high and final 1)");
    mApp->add_option("--motion-light", mMotionLight,
        "motion blur: follow (each slab sample lit where its material was in the still field, each shutter layer where "
        "its own was, as the reference carries each point's light along its path) or still (lit by the still field's "
        "light where the material is now: the shutter's mid-time shadows, faster, but a rising fire is lit above its own "
        "shadow: pyro 4 dB and a Mantaflow fire 10 dB further from the reference at default) "
        "(default: " + std::string(mb.lightFollows ? "follow" : "still") + "; draft still)");
    mApp->add_option("--lens-samples", mLensSamples,
        "depth of field: sub-frames, each through its own part of the lens (rings of sectors of equal area) and blurred by "
        "that part's circle of confusion, averaged; widened kernels blur optical depth where a camera averages images, so "
        "thick media need more to converge (docs/equations.md#depth-of-field); with motion blur, the larger of it and "
        "--motion-samples, each sub-frame a part of both; about N times the time; range [1, 1024] (default: 4; draft 1, high 8, final 16)");
    mApp->add_option("--blur-samples", mBlurSamples,
        "--method raymarch with motion blur or depth of field: rays per pixel, each at its own shutter time and lens point, "
        "averaged; range [1, 4096] (default: " + std::to_string(RenderSettings().blurSamples) + ")");
    mApp->add_option("--pixel-samples", mPixelSamples,
        "--method raymarch: rays per pixel, spread over the pixel's square (Halton points, rotated per pixel) and averaged: "
        "a box filter as a camera's pixel, the anti-aliased reference; with motion blur or depth of field the larger of it and "
        "--blur-samples, each ray also at its own time and lens point; range [1, 4096] (default: 1, the pixel's centre ray)");
    mApp->add_option("--samples", mSamples,
        "--method pathtrace: paths per pixel, spread over the pixel's square, in [1, 1048576] (default: " + std::to_string(rs.pathSamples) +
            "); level sets: vdb_render's rays per pixel, accepted for compatibility, the EWA filter anti-aliases without extra samples");
    mApp->add_option("--threads,--cpus", mThreads,
        "worker threads, 0 = the CPUs the farm task or container was granted ($SLURM_CPUS_PER_TASK, the cgroup's quota), "
        "else all cores; range [0, 1024] (default: 0; docs/farm.md)");
    mApp->add_option("--simd", mSimd,
        "on: the volume rasteriser uses the CPU's vector unit (AVX-512 or AVX2, detected at run time; images within "
        "1e-5 of off); off: one pixel at a time, the reference it is tested against (default: on)");
    mApp->add_option("--cull", mCull,
        "fog volumes: on: the streamed frame, bricks (leaf nodes, active tiles) composited front to back in depth windows, "
        "those behind opaque screen tiles never expanded into kernels, light marched where it is looked up (images within 1e-5 of "
        "off); off: every kernel built and projected and every light ray marched, the reference it is tested against (default: on; "
        "docs/architecture.md#the-streamed-frame)");
    mApp->add_option("--max-memory", mMaxMemory,
        "memory budget of a frame in bytes, with an optional K, M, G or T suffix (powers of 1024), range [64M, 1e18]; "
        "a frame that would need more stops before allocating it (exit 5) (default: 0 = 3/4 of the memory the farm task or container "
        "was granted ($SLURM_MEM_PER_NODE, the cgroup's limit), else of the physical memory)");
    mOutputOptions.add(mApp);
}

CameraSettings RenderOptions::cameraFor(std::optional<int> frame) const
{
    CameraSettings cam;
    if (!mCameraFile.empty()) {
        cam = readCameraFile(frame ? framePath(mCameraFile, *frame) : mCameraFile, frame.value_or(0));
        // A rotation or a target given here replaces the file's, whichever it had.
        if (!mRotate.empty()) cam.lookAt.reset();
        if (!mLookAt.empty()) cam.rotate.reset();
    }
    if (!mRes.empty()) parseResolution(mRes, cam.width, cam.height);
    if (!mTranslate.empty()) cam.translate = parseVec3("translate", mTranslate, true);
    if (!mRotate.empty()) cam.rotate = parseVec3("rotate", mRotate, true);
    if (!mLookAt.empty()) cam.lookAt = parseVec3("lookat", mLookAt, true);
    if (!mUp.empty()) cam.up = parseVec3("up", mUp, true);
    if (!mCamera.empty()) {
        if (mCamera.rfind("persp", 0) == 0) cam.projection = Projection::Perspective;
        else if (mCamera.rfind("ortho", 0) == 0) cam.projection = Projection::Orthographic;
        else throw ValueError("--camera: expected perspective or orthographic, got '" + mCamera + "'");
    }
    if (mFov && mFocal) throw ValueError("specify --focal or --fov, but not both");
    if (mAperture) cam.aperture = *mAperture;
    if (mFocal) cam.focal = *mFocal;
    if (mFov) cam.setFieldOfView(*mFov);
    if (mFrame) cam.frame = *mFrame;
    if (mNear) cam.near = *mNear;
    if (mFar) cam.far = *mFar;
    if (mFstop) cam.fstop = *mFstop;
    if (mFocusDistance) cam.focusDistance = *mFocusDistance;
    return cam;
}

void RenderOptions::resolve(std::optional<int> frame, CameraSettings& cam, RenderSettings& rs) const
{
    if (!mQuality.empty()) rs = RenderSettings::preset(parseChoice("quality", mQuality, kQualities));
    cam = cameraFor(frame);
    if (!mAbsorb.empty()) rs.medium.absorb = parseVec3("absorb", mAbsorb, true);
    if (!mScatter.empty()) rs.medium.scatter = parseVec3("scatter", mScatter, true);
    if (!mEmission.empty()) rs.medium.emission = parseVec3("emission", mEmission, true);
    if (!mAmbient.empty()) rs.ambient = parseVec3("ambient", mAmbient, true);
    if (!mAddVolumeTransforms.empty() && mAddVolumeTransforms.size() != mAddVolumes.size()) {
        throw ValueError("--add-volume-transform: " + std::to_string(mAddVolumeTransforms.size()) + " given for " +
                         std::to_string(mAddVolumes.size()) + " --add-volume; give one for each, in the same order");
    }
    for (std::size_t i = 0; i < mAddVolumeTransforms.size(); ++i) addedVolumeTransform(i); // each checked before any file is read
    if (!mAddVolumeMaterials.empty() && mAddVolumeMaterials.size() != mAddVolumes.size()) {
        throw ValueError("--add-volume-material: " + std::to_string(mAddVolumeMaterials.size()) + " given for " +
                         std::to_string(mAddVolumes.size()) + " --add-volume; give one for each, in the same order ('same': the input's)");
    }
    for (std::size_t i = 0; i < mAddVolumeMaterials.size(); ++i) addedVolumeMaterial(i);
    if (!mLights.empty()) {
        const Light defaults;
        rs.lights.clear();
        for (const std::string& text : mLights) {
            const std::vector<double> v = parseNumbers("light", text);
            if (v.size() != 3 && v.size() != 6) throw ValueError("--light: expected X,Y,Z or X,Y,Z,R,G,B, got '" + text + "'");
            Light light = defaults;
            light.direction = Vec3d(v[0], v[1], v[2]);
            if (v.size() == 6) light.color = Vec3d(v[3], v[4], v[5]);
            rs.lights.push_back(light);
        }
    }
    if (!mPointLights.empty() || !mSpotLights.empty()) {
        rs.pointLights.clear();
        for (const std::string& text : mPointLights) {
            const std::vector<double> v = parseNumbers("point-light", text);
            if (v.size() != 3 && v.size() != 6) throw ValueError("--point-light: expected X,Y,Z or X,Y,Z,R,G,B, got '" + text + "'");
            PointLight light;
            light.position = Vec3d(v[0], v[1], v[2]);
            if (v.size() == 6) light.color = Vec3d(v[3], v[4], v[5]);
            rs.pointLights.push_back(light);
        }
        for (const std::string& text : mSpotLights) {
            const std::vector<double> v = parseNumbers("spot-light", text);
            if (v.size() != 7 && v.size() != 8 && v.size() != 11) {
                throw ValueError("--spot-light: expected X,Y,Z,TX,TY,TZ,ANGLE[,BLEND[,R,G,B]], got '" + text + "'");
            }
            PointLight light;
            light.position = Vec3d(v[0], v[1], v[2]);
            light.spotTarget = Vec3d(v[3], v[4], v[5]);
            light.spotAngle = v[6];
            if (!(v[6] > 0.0 && v[6] <= 180.0)) throw ValueError("--spot-light: the cone ANGLE must be in (0, 180] degrees, got '" + text + "'");
            if (v.size() >= 8) light.spotBlend = v[7];
            if (v.size() == 11) light.color = Vec3d(v[8], v[9], v[10]);
            rs.pointLights.push_back(light);
        }
    }
    if (mPointLightRadius) {
        for (PointLight& light : rs.pointLights) light.radius = *mPointLightRadius;
    }
    if (!mEmissionColor.empty()) rs.gridEmission.color = parseVec3("emission-color", mEmissionColor, true);
    if (mEmissionIntensity) rs.gridEmission.intensity = *mEmissionIntensity;
    if (mKelvinScale) rs.gridEmission.kelvinScale = *mKelvinScale;
    if (mKelvinOffset) rs.gridEmission.kelvinOffset = *mKelvinOffset;
    if (mBlackbodyIntensity) rs.gridEmission.blackbodyIntensity = *mBlackbodyIntensity;
    mEnvironmentLightCount = 0;
    if (!mEnvironment.empty()) {
        // Read once: validate() and run() both resolve.
        if (!mEnvironmentFill) mEnvironmentFill = environmentLights(readLatLongImage(mEnvironment), mEnvironmentLights, mEnvironmentIntensity);
        const std::vector<Light>& fill = *mEnvironmentFill;
        if (rs.lights.size() + fill.size() > kMaxLights) {
            throw ValueError("--environment-lights: " + std::to_string(fill.size()) + " environment lights and " + std::to_string(rs.lights.size()) +
                             " --light options exceed " + std::to_string(kMaxLights) + " lights");
        }
        rs.lights.insert(rs.lights.end(), fill.begin(), fill.end());
        mEnvironmentLightCount = fill.size();
    }
    if (mGain) rs.shadow.gain = *mGain;
    if (mCutoff) rs.cutoff = *mCutoff;
    if (mShadowStep) rs.shadow.step = *mShadowStep;
    if (mShadowRes) rs.shadow.resolution = *mShadowRes;
    if (mStep) rs.step = *mStep;
    if (!mMethod.empty()) rs.method = parseChoice("method", mMethod, kMethods);
    if (mKernelSigma) rs.splat.kernelSigma = *mKernelSigma;
    if (mSurfaceSigma) rs.surface.sigma = *mSurfaceSigma;
    if (mLowpass) rs.splat.lowpass = *mLowpass;
    if (!mAa.empty()) rs.splat.antiAliasing = parseChoice("aa", mAa, kAntiAliasing);
    if (mCutoffRadius) rs.splat.cutoffRadius = *mCutoffRadius;
    if (!mExp.empty()) rs.splat.expEvaluation = parseChoice("exp", mExp, kExpEvaluations);
    if (!mRenormalize.empty()) rs.splat.renormalize = parseChoice("renormalize", mRenormalize, kOnOff);
    if (!mTaper.empty()) rs.splat.taper = parseChoice("taper", mTaper, kOnOff);
    if (!mPrefilter.empty()) rs.splat.prefilter = parseChoice("prefilter", mPrefilter, kOnOff);
    if (mTileSpacing) rs.splat.tileKernelSpacing = *mTileSpacing;
    if (mRefine) rs.splat.refine = *mRefine;
    if (mRefineEmission) rs.splat.refineEmission = *mRefineEmission;
    if (!mPrecision.empty()) rs.splat.doublePrecision = parseChoice("precision", mPrecision, kPrecisions);
    if (mSlab) rs.splat.slab = *mSlab;
    if (mLod) rs.splat.lodPixels = *mLod;
    if (mLodError) rs.splat.lodError = *mLodError;
    if (!mImageLod.empty()) rs.splat.imageLod = parseImageLod(mImageLod);
    if (!mImageLodComposite.empty()) rs.splat.imageLodComposite = parseChoice("image-lod-composite", mImageLodComposite, kOnOff);
    if (mPixelSize) rs.splat.pixelSize = *mPixelSize;
    if (mPixelSizeBlur) rs.splat.pixelSizeBlur = *mPixelSizeBlur;
    if (mSupersample) rs.splat.supersample = *mSupersample;
    if (mSupersampleSpan) rs.splat.supersampleSpan = *mSupersampleSpan;
    if (mIsovalue) rs.surface.isovalue = *mIsovalue;
    if (mIso) rs.surface.iso = *mIso;
    if (mIsoOpacity) rs.surface.isoOpacity = *mIsoOpacity;
    if (!mShader.empty()) rs.surface.shader = parseChoice("shader", mShader, kShaders);
    if (mSamples && *mSamples < 1) throw ValueError("--samples must be >= 1");
    if (mSamples && rs.method == Method::PathTrace) rs.pathSamples = *mSamples;
    if (mBounces) rs.bounces = *mBounces;
    if (mAnisotropy) rs.scattering.anisotropy = *mAnisotropy;
    if (mOctaves) rs.scattering.octaves = *mOctaves;
    if (mOctaveScatter) rs.scattering.octaveScatter = *mOctaveScatter;
    if (mOctaveExtinction) rs.scattering.octaveExtinction = *mOctaveExtinction;
    if (mOctaveAnisotropy) rs.scattering.octaveAnisotropy = *mOctaveAnisotropy;
    if (rs.method == Method::PathTrace) {
        if (mGain && *mGain != 0.0) throw ValueError("--gain: --method pathtrace's shadows are physical (gain 0); leave --gain out or give 0");
        rs.shadow.gain = 0.0;
    }
    if (!mSimd.empty()) rs.simd = parseChoice("simd", mSimd, kOnOff);
    if (!mCull.empty()) rs.cull = parseChoice("cull", mCull, kOnOff);
    if (mVelocityScale) rs.motionBlur.velocityScale = *mVelocityScale;
    if (!mVelocityUnit.empty()) rs.motionBlur.unit = parseChoice("velocity-unit", mVelocityUnit, kVelocityUnits);
    if (mFps) rs.motionBlur.fps = *mFps;
    if (!mShutter.empty()) {
        const std::vector<double> v = parseNumbers("shutter", mShutter);
        if (v.size() != 2) throw ValueError("--shutter: expected OPEN,CLOSE in frames, got '" + mShutter + "'");
        rs.motionBlur.shutterOpen = v[0];
        rs.motionBlur.shutterClose = v[1];
    }
    if (mBlurSamples) rs.blurSamples = *mBlurSamples;
    if (mPixelSamples) rs.pixelSamples = *mPixelSamples;
    if (mMotionSamples) rs.motionBlur.samples = *mMotionSamples;
    if (mMotionSplit) rs.motionBlur.splitSigmas = *mMotionSplit;
    if (mMotionLayers) rs.motionBlur.layers = *mMotionLayers;
    if (!mMotionLight.empty()) rs.motionBlur.lightFollows = parseChoice("motion-light", mMotionLight, kMotionLights);
    if (mLensSamples) rs.lensSamples = *mLensSamples;
    const GrantedSettings granted = grantedExecution();
    rs.threads = granted.threads;
    rs.maxMemory = granted.maxMemory;
}

GrantedSettings RenderOptions::grantedExecution() const
{
    return grantedSettings(mThreads, mMaxMemory.empty() ? 0.0 : parseBytes("max-memory", mMaxMemory));
}

std::string RenderOptions::grantedText() const { return grantedExecution().text; }

RenderSettings RenderOptions::prepare(const std::string& output, const std::string& preview, const RenderSettings& given,
    std::vector<std::string>& warnings, bool attachedVelocity)
{
    mOutputOptions.prepare(output, preview, warnings); // colour config, spaces, output paths
    RenderSettings working = given;
    mOutputOptions.toWorkingSpace(working, warnings);
    ignoredOptionWarnings(warnings, attachedVelocity);
    if (!mTemperatureGrid.empty() && !mOutputOptions.hasLinearRec709()) {
        warnings.push_back("--temperature: the OCIO config has no linear Rec.709 space, so the blackbody's Rec.709 colours are taken as "
                           "working-space values (--ocio-config)");
    }
    return working;
}

std::vector<std::string> RenderOptions::cameraWarnings(const Camera& camera)
{
    std::vector<std::string> warnings;
    if (camera.looksDownZByDefault()) {
        warnings.push_back("the eye is at the grid's centre, the default target: looking down -z (--translate or --lookat frame it)");
    }
    if (camera.upReplacedByDefault()) {
        warnings.push_back("the grid's centre lies along --up from the eye: another world axis is the image's up (--up, --translate or "
                           "--lookat frame it)");
    }
    return warnings;
}

GridSource RenderOptions::open(const std::string& path) const { return withExtraGrids(GridSource::open(path, mName)); }

GridSource RenderOptions::withExtraGrids(const GridSource& opened) const
{
    // --velocity-grid: each volume's own, attached before the sum so that each keeps its motion
    // (withAddedVolume); a volume whose file has none stands still, as long as one volume has it.
    std::exception_ptr noVelocity;
    const auto moving = [&](const GridSource& volume) {
        if (mVelocityGrid.empty()) return volume;
        try {
            return volume.withVelocityGrid(mVelocityGrid);
        } catch (const InputError&) {
            if (!noVelocity) noVelocity = std::current_exception();
            return volume;
        }
    };
    GridSource summed = moving(opened);
    bool moves = summed.hasVelocityGrid();
    for (std::size_t i = 0; i < mAddVolumes.size(); ++i) {
        const auto [file, grid] = splitVolume(mAddVolumes[i]);
        const GridSource opened = GridSource::open(file, grid);
        const GridSource added = moving(mAddVolumeTransforms.empty() ? opened : opened.transformed(addedVolumeTransform(i)));
        moves = moves || added.hasVelocityGrid();
        const std::optional<VolumeMaterial> material = mAddVolumeMaterials.empty() ? std::nullopt : addedVolumeMaterial(i);
        if (!material) {
            summed = summed.withAddedVolume(added);
            continue;
        }
        GridSource own = material->color.empty() ? added : added.withColorGrid(material->color);
        if (!material->emissionGrid.empty()) own = own.withEmissionGrid(material->emissionGrid);
        if (!material->temperature.empty()) own = own.withTemperatureGrid(material->temperature);
        summed = summed.withAddedVolume(own, material->medium);
    }
    if (noVelocity && !moves) std::rethrow_exception(noVelocity);
    GridSource grid = mColor.empty() ? summed : summed.withColorGrid(mColor);
    if (!mEmissionGrid.empty()) grid = grid.withEmissionGrid(mEmissionGrid);
    if (!mTemperatureGrid.empty()) grid = grid.withTemperatureGrid(mTemperatureGrid);
    return grid;
}

Attributes RenderOptions::headerAttributes(const GridSource& grid, const Camera& camera, const RenderSettings& settings,
    const std::string& input, double renderSeconds, std::optional<int> frame, const RenderStats& stats) const
{
    // What a lighter looks for in a file: the version, preset, host and render time.
    Attributes attributes{{"software", std::string("vdb_ewa ") + versionString()}, {"vdb_ewa/input", input},
        {"vdb_ewa/grid", grid.name()}, {"vdb_ewa/quality", mQuality.empty() ? "default" : mQuality}, {"vdb_ewa/host", hostName()},
        {"vdb_ewa/render-seconds", fmt(std::round(renderSeconds * 1000.0) / 1000.0)}};
    if (frame) attributes.emplace_back("vdb_ewa/frame", std::to_string(*frame));
    attributes.emplace_back("vdb_ewa/camera-record", cameraRecord(explicitCamera(camera, grid.worldCentre())));
    for (const Attributes& group : resolvedOptions(grid, camera, settings))
        for (const auto& [key, value] : group) {
            // The thread count never changes the image; leaving it out keeps the headers of
            // two thread counts the same (but for the render time).
            if (key != "threads") attributes.emplace_back("vdb_ewa/" + key, value);
        }
    for (auto& counter : statsAttributes(stats)) attributes.push_back(std::move(counter));
    return attributes;
}

Attributes RenderOptions::statsAttributes(const RenderStats& s)
{
    const auto n = [](std::uint64_t v) { return std::to_string(v); };
    Attributes out{{"active-voxels", n(s.activeVoxels)}, {"active-tiles", n(s.activeTiles)}, {"kernels", n(s.kernels)},
        {"kernels-projected", n(s.splats)}, {"splat-tile-pairs", n(s.splatTilePairs)},
        {"splat-tile-pairs-composited", n(s.splatTilePairs - std::min(s.splatTilePairs, s.splatTilePairsSkipped))}};
    if (s.streamed) {
        out.insert(out.end(), {{"bricks", n(s.bricks)}, {"bricks-expanded", n(s.bricksExpanded)}, {"bricks-hidden", n(s.bricksHidden)},
                                  {"bricks-outside", n(s.bricksOutside)}, {"depth-windows", n(s.windows)},
                                  {"splats-in-flight", n(s.splatsInFlight)}});
    }
    if (s.footprintSamples > 0) {
        out.insert(out.end(), {{"footprint-samples", n(s.footprintSamples)},
                                  {"footprint-samples-by-level", n(s.footprintSamplesAtLevel[0]) + "," + n(s.footprintSamplesAtLevel[1]) + "," +
                                                                     n(s.footprintSamplesAtLevel[2]) + "," + n(s.footprintSamplesAtLevel[3])},
                                  {"slab-composites", n(s.slabComposites)},
                                  {"slab-composites-by-level", n(s.slabCompositesAtLevel[0]) + "," + n(s.slabCompositesAtLevel[1]) + "," +
                                                                   n(s.slabCompositesAtLevel[2]) + "," + n(s.slabCompositesAtLevel[3])}});
    }
    if (s.lightRays > 0) out.insert(out.end(), {{"light-rays", n(s.lightRays)}, {"light-rays-marched", n(s.lightRaysMarched)}});
    if (s.lightMapsReused > 0) out.insert(out.end(), {{"light-maps-reused", n(s.lightMapsReused)}, {"light-rays-reused", n(s.lightRaysReused)}});
    if (s.pixelSize > 1) out.emplace_back("pixel-size-used", std::to_string(s.pixelSize));
    if (s.supersample > 1) {
        out.insert(out.end(), {{"supersampled", std::to_string(s.supersample)},
                                  {"supersampled-window", std::to_string(s.supersampleWindow[0]) + "," + std::to_string(s.supersampleWindow[1]) + "," +
                                                              std::to_string(s.supersampleWindow[2]) + "," + std::to_string(s.supersampleWindow[3])}});
    }
    if (s.movingKernels > 0) out.insert(out.end(), {{"kernels-moving", n(s.movingKernels)}, {"motion-sub-kernels", n(s.motionSubKernels)}});
    // Not deterministic (the process's, and the allocator's): left out where files are compared.
    out.emplace_back("peak-memory-mb", fmt(std::round(double(s.peakResidentBytes) / 1e5) / 10.0));
    if (s.activeVoxels > 0) {
        out.emplace_back("peak-bytes-per-active-voxel", fmt(std::round(double(s.peakResidentBytes) / double(s.activeVoxels) * 10.0) / 10.0));
    }
    for (auto& [key, value] : out) key = "vdb_ewa/" + key;
    return out;
}

std::vector<Attributes> RenderOptions::resolvedOptions(const GridSource& grid, const Camera& camera, const RenderSettings& rs) const
{
    const CameraSettings& c = camera.settings();
    Attributes cameraGroup{{"camera", c.projection == Projection::Perspective ? "perspective" : "orthographic"},
        {"res", std::to_string(c.width) + "x" + std::to_string(c.height)}, {"translate", fmt3(c.translate)}};
    if (c.rotate) {
        cameraGroup.emplace_back("rotate", fmt3(*c.rotate));
    } else {
        cameraGroup.emplace_back("lookat", fmt3(c.lookAt ? *c.lookAt : grid.worldCentre()));
        cameraGroup.emplace_back("up", fmt3(c.up));
    }
    for (const auto& [k, v] : Attributes{{"focal", fmt(c.focal)}, {"aperture", fmt(c.aperture)}, {"fov", fmt(c.fieldOfView())},
             {"frame", fmt(c.frame)}, {"near", fmt(c.near)}, {"far", fmt(c.far)}})
        cameraGroup.emplace_back(k, v);
    if (c.fstop > 0.0) {
        cameraGroup.emplace_back("fstop", fmt(c.fstop));
        cameraGroup.emplace_back("focus-distance", fmt(camera.focusDepth()));
    }
    Attributes model{{"absorb", fmt3(rs.medium.absorb)}, {"scatter", fmt3(rs.medium.scatter)}, {"emission", fmt3(rs.medium.emission)},
        {"light", lightsText({rs.lights.begin(), rs.lights.end() - std::ptrdiff_t(mEnvironmentLightCount)})}, {"ambient", fmt3(rs.ambient)},
        {"anisotropy", fmt(rs.scattering.anisotropy)}, {"multiple-scattering", std::to_string(rs.scattering.octaves)}};
    if (rs.scattering.octaves > 1) {
        model.emplace_back("octave-scatter", fmt(rs.scattering.octaveScatter));
        model.emplace_back("octave-extinction", fmt(rs.scattering.octaveExtinction));
        model.emplace_back("octave-anisotropy", fmt(rs.scattering.octaveAnisotropy));
    }
    for (const auto& [k, v] : Attributes{{"gain", fmt(rs.shadow.gain)}, {"cutoff", fmt(rs.cutoff)}, {"shadowstep", fmt(rs.shadow.step)},
             {"shadow-res", fmt(rs.shadow.resolution)}})
        model.emplace_back(k, v);
    if (!rs.pointLights.empty()) {
        const auto [points, spots] = pointLightsText(rs.pointLights);
        if (!points.empty()) model.emplace_back("point-light", points);
        if (!spots.empty()) model.emplace_back("spot-light", spots);
        model.emplace_back("point-light-radius", fmt(rs.pointLights.front().radius));
    }
    if (grid.hasColorGrid()) model.emplace_back("color", mColor);
    if (!mEnvironment.empty()) {
        model.emplace_back("environment", mEnvironment);
        model.emplace_back("environment-lights", std::to_string(mEnvironmentLights));
        model.emplace_back("environment-intensity", fmt(mEnvironmentIntensity));
    }
    if (grid.hasEmissionGrid()) {
        model.emplace_back("emission-grid", mEmissionGrid);
        model.emplace_back("emission-color", fmt3(rs.gridEmission.color));
        model.emplace_back("emission-intensity", fmt(rs.gridEmission.intensity));
    }
    if (grid.hasTemperatureGrid()) {
        model.emplace_back("temperature", mTemperatureGrid);
        model.emplace_back("temperature-scale", fmt(rs.gridEmission.kelvinScale));
        model.emplace_back("temperature-offset", fmt(rs.gridEmission.kelvinOffset));
        model.emplace_back("blackbody-intensity", fmt(rs.gridEmission.blackbodyIntensity));
    }
    if (!mAddVolumes.empty()) {
        std::string volumes;
        for (const std::string& v : mAddVolumes) volumes += (volumes.empty() ? "" : "; ") + v;
        model.emplace_back("add-volume", volumes);
    }
    if (!mAddVolumeMaterials.empty()) {
        std::string materials;
        for (const std::string& m : mAddVolumeMaterials) materials += (materials.empty() ? "" : "; ") + m;
        model.emplace_back("add-volume-material", materials);
    }
    if (!mAddVolumeTransforms.empty()) {
        std::string transforms;
        for (const std::string& t : mAddVolumeTransforms) transforms += (transforms.empty() ? "" : "; ") + t;
        model.emplace_back("add-volume-transform", transforms);
    }
    if (grid.hasVelocityGrid()) {
        model.emplace_back("velocity-grid", mVelocityGrid.empty() ? std::string("(attached to the grid)") : mVelocityGrid);
        model.emplace_back("velocity-scale", fmt(rs.motionBlur.velocityScale));
        model.emplace_back("velocity-unit", choiceName(rs.motionBlur.unit, kVelocityUnits));
        model.emplace_back("fps", fmt(rs.motionBlur.fps));
        model.emplace_back("shutter", fmt(rs.motionBlur.shutterOpen) + "," + fmt(rs.motionBlur.shutterClose));
        model.emplace_back("motion-samples", std::to_string(rs.motionBlur.samples));
        model.emplace_back("motion-split", fmt(rs.motionBlur.splitSigmas));
        model.emplace_back("motion-layers", std::to_string(rs.motionBlur.layers));
        model.emplace_back("motion-light", choiceName(rs.motionBlur.lightFollows, kMotionLights));
    }
    Attributes method{{"method", choiceName(rs.method, kMethods)}};
    if (rs.method != Method::Splat && rs.method != Method::PathTrace) method.emplace_back("step", fmt(rs.step));
    if (rs.method != Method::Splat && (grid.hasVelocityGrid() || c.fstop > 0.0)) method.emplace_back("blur-samples", std::to_string(rs.blurSamples));
    if (rs.method != Method::Splat && rs.method != Method::PathTrace) method.emplace_back("pixel-samples", std::to_string(rs.pixelSamples));
    if (rs.method == Method::PathTrace) {
        method.emplace_back("samples", std::to_string(rs.pathSamples));
        method.emplace_back("bounces", std::to_string(rs.bounces));
    }
    if (rs.method == Method::Splat && c.fstop > 0.0 && !grid.isLevelSet()) method.emplace_back("lens-samples", std::to_string(rs.lensSamples));
    if (!grid.isLevelSet() && !std::isnan(rs.surface.iso)) {
        method.emplace_back("iso", fmt(rs.surface.iso));
        method.emplace_back("iso-opacity", fmt(rs.surface.isoOpacity));
        method.emplace_back("surface-sigma", fmt(rs.surface.sigma));
    }
    if (grid.isLevelSet()) {
        method.emplace_back("isovalue", fmt(rs.surface.isovalue));
        method.emplace_back("shader", choiceName(rs.surface.shader, kShaders));
        method.emplace_back("surface-sigma", fmt(rs.surface.sigma));
    }
    for (const auto& [k, v] : Attributes{{"kernel-sigma", fmt(rs.splat.kernelSigma)}, {"prefilter", choiceName(rs.splat.prefilter, kOnOff)}, {"lowpass", fmt(rs.splat.lowpass)},
             {"aa", choiceName(rs.splat.antiAliasing, kAntiAliasing)}, {"cutoff-radius", fmt(rs.splat.cutoffRadius)},
             {"renormalize", choiceName(rs.splat.renormalize, kOnOff)}, {"taper", choiceName(rs.splat.taper, kOnOff)}, {"exp", choiceName(rs.splat.expEvaluation, kExpEvaluations)},
             {"precision", choiceName(rs.splat.doublePrecision, kPrecisions)}, {"slab", fmt(rs.splat.slab)},
             {"tile-spacing", std::to_string(rs.splat.tileKernelSpacing)}, {"refine", std::to_string(rs.splat.refine)}, {"refine-emission", std::to_string(rs.splat.refineEmission)}, {"lod", fmt(rs.splat.lodPixels)}, {"lod-error", fmt(rs.splat.lodError)},
             {"image-lod", imageLodName(rs.splat.imageLod)}, {"image-lod-composite", choiceName(rs.splat.imageLodComposite, kOnOff)},
             {"pixel-size", std::to_string(rs.splat.pixelSize)}, {"pixel-size-blur", fmt(rs.splat.pixelSizeBlur)},
             {"supersample", std::to_string(rs.splat.supersample)}, {"supersample-span", fmt(rs.splat.supersampleSpan)},
             {"threads", std::to_string(rs.threads)}, {"simd", choiceName(rs.simd, kOnOff)}, {"cull", choiceName(rs.cull, kOnOff)}})
        method.emplace_back(k, v);
    return {cameraGroup, model, method, mOutputOptions.resolved()};
}

void RenderOptions::ignoredOptionWarnings(std::vector<std::string>& warnings, bool attachedVelocity) const
{
    const auto given = [&](const char* name) { return mApp->get_option(name)->count() > 0; };
    const std::pair<const char*, std::vector<const char*>> groups[] = {
        {"--emission-grid", {"--emission-color", "--emission-intensity"}},
        {"--temperature", {"--temperature-scale", "--temperature-offset", "--blackbody-intensity"}},
        {"--environment", {"--environment-lights", "--environment-intensity"}},
        {"--velocity-grid", {"--velocity-scale", "--velocity-unit", "--fps", "--shutter", "--motion-samples", "--motion-split", "--motion-layers", "--motion-light"}},
        {"--fstop", {"--focus-distance", "--lens-samples"}}};
    if (given("--point-light-radius") && !given("--point-light") && !given("--spot-light")) {
        warnings.push_back("--point-light-radius changes nothing without --point-light or --spot-light");
    }
    for (const auto& [main, qualifiers] : groups) {
        if (given(main) || (attachedVelocity && std::string(main) == "--velocity-grid")) continue;
        for (const char* q : qualifiers) {
            if (given(q)) warnings.push_back(std::string(q) + " changes nothing without " + main);
        }
    }
}

std::string RenderOptions::lightsText(const std::vector<Light>& lights, const std::string& separator)
{
    std::string out;
    for (const Light& l : lights) out += (out.empty() ? "" : separator) + fmt3(l.direction) + "," + fmt3(l.color);
    return out.empty() ? "none" : out;
}

std::pair<std::string, std::string> RenderOptions::pointLightsText(const std::vector<PointLight>& lights)
{
    std::string points, spots;
    for (const PointLight& l : lights) {
        if (l.spotAngle > 0.0) {
            spots += (spots.empty() ? "" : "; ") + fmt3(l.position) + "," + fmt3(l.spotTarget) + "," + fmt(l.spotAngle) + "," + fmt(l.spotBlend) + "," + fmt3(l.color);
        } else {
            points += (points.empty() ? "" : "; ") + fmt3(l.position) + "," + fmt3(l.color);
        }
    }
    return {points, spots};
}

Mat4d RenderOptions::addedVolumeTransform(std::size_t i) const
{
    const std::string& text = mAddVolumeTransforms[i];
    const std::string where = "--add-volume-transform " + std::to_string(i + 1) + " ('" + text.substr(0, 120) + "')";
    const std::vector<double> v = parseNumbers("add-volume-transform", text);
    if (v.size() != 12 && v.size() != 16) throw ValueError(where + ": expected 16 numbers (a 4x4 matrix row by row) or its first 12");
    Mat4d m(1.0);
    for (std::size_t k = 0; k < v.size(); ++k) {
        if (!std::isfinite(v[k])) throw ValueError(where + ": every number must be finite");
        m[int(k % 4)][int(k / 4)] = v[k]; // GLM: column, row
    }
    if (m[0][3] != 0.0 || m[1][3] != 0.0 || m[2][3] != 0.0 || m[3][3] != 1.0) {
        throw ValueError(where + ": the last row must be 0,0,0,1 (an affine transform)");
    }
    if (!(std::abs(glm::determinant(Mat3d(m))) > 1e-300)) throw ValueError(where + ": the matrix is singular");
    return m;
}

std::optional<RenderOptions::VolumeMaterial> RenderOptions::addedVolumeMaterial(std::size_t i) const
{
    const std::string& text = mAddVolumeMaterials[i];
    const std::string where = "--add-volume-material " + std::to_string(i + 1) + " ('" + text.substr(0, 120) + "')";
    std::istringstream words(text);
    std::string word;
    VolumeMaterial m;
    if (!mAbsorb.empty()) m.medium.absorb = parseVec3("absorb", mAbsorb, true);
    if (!mScatter.empty()) m.medium.scatter = parseVec3("scatter", mScatter, true);
    if (!mEmission.empty()) m.medium.emission = parseVec3("emission", mEmission, true);
    bool any = false, same = false;
    while (words >> word) {
        if (word == "same") {
            same = true;
            continue;
        }
        any = true;
        const std::size_t eq = word.find('=');
        const std::string key = word.substr(0, eq), value = eq == std::string::npos ? "" : word.substr(eq + 1);
        if (eq == std::string::npos || value.empty()) throw ValueError(where + ": expected KEY=VALUE words, got '" + word.substr(0, 60) + "'");
        if (key == "absorb" || key == "scatter" || key == "emission") {
            Vec3d v;
            try {
                v = parseVec3(key, value, true);
            } catch (const ValueError&) {
                throw ValueError(where + ": " + key + ": expected R,G,B or one number, got '" + value.substr(0, 60) + "'");
            }
            for (int c = 0; c < 3; ++c) {
                if (!(v[c] >= 0.0 && v[c] <= 1e6)) throw ValueError(where + ": " + key + ": each component must be in [0, 1e6]");
            }
            (key == "absorb" ? m.medium.absorb : key == "scatter" ? m.medium.scatter : m.medium.emission) = v;
        } else if (key == "color" || key == "emission-grid" || key == "temperature") {
            (key == "color" ? m.color : key == "emission-grid" ? m.emissionGrid : m.temperature) = value;
        } else {
            throw ValueError(where + ": unknown key '" + key.substr(0, 60) + "' (absorb, scatter, emission, color, emission-grid, temperature)");
        }
    }
    if (same && any) throw ValueError(where + ": 'same' takes the input's optical model; give it alone, or KEY=VALUE words without it");
    if (!same && !any) throw ValueError(where + ": empty; give KEY=VALUE words, or 'same' for the input's optical model");
    if (same) return std::nullopt;
    return m;
}

std::pair<std::string, std::string> RenderOptions::splitVolume(const std::string& volume)
{
    // The whole text where it names a file: a path may hold a colon.
    const std::size_t colon = volume.rfind(':');
    if (colon == std::string::npos || std::filesystem::exists(volume)) return {volume, ""};
    return {volume.substr(0, colon), volume.substr(colon + 1)};
}

std::vector<std::string> RenderOptions::addedVolumeFiles() const
{
    std::vector<std::string> files;
    for (const std::string& volume : mAddVolumes) files.push_back(splitVolume(volume).first);
    return files;
}

} // namespace vdb_ewa::cli
