/// @file render_settings.h
/// @brief Plain settings of the optical model and of the EWA splatter, with defaults.
/// @note The optical model and its defaults are vdb_render's (OpenVDB tools/RayTracer.h,
///       VolumeRender): extinction (absorb + scatter) x density per voxel length, single
///       scattering of directional lights with shadow transmittance (vdb_render has one).
#pragma once

#include "types.h"

#include <limits>
#include <vector>

namespace vdb_ewa {

/// Screen-space anti-aliasing of the footprints (Zwicker et al. 2002, Sec. 5, Eq. 33).
enum class AntiAliasing
{
    Ewa,  ///< EWA resampling filter: footprint covariance + low-pass covariance (Eq. 33)
    Floor, ///< each principal footprint variance raised to at least the low-pass variance: EWA's
           ///< filter where kernels are minified, no extra blur where they span pixels
    Swan, ///< Swan et al.: scale the whole footprint uniformly (comparison mode, over-blurs)
    None  ///< no low-pass filter: point-sample the projected kernel (aliases when minified)
};

/// How the rasteriser evaluates exp(-r/2) over a footprint (Sec. 7.1).
enum class ExpEvaluation
{
    Incremental, ///< forward differencing in the exponential domain: two multiplications a pixel
    Exact,       ///< std::exp at every pixel
    Table        ///< the paper's 1D table indexed by r (1024 entries, linear interpolation)
};

/// Quality presets: named bundles of the speed/accuracy knobs (docs/performance.md).
enum class Quality { Draft, Default, High, Final };

/// Level-set shaders, vdb_render's (OpenVDB tools/RayTracer.h), white material.
enum class SurfaceShader
{
    Diffuse,  ///< |N . ray direction|: a light at the camera
    Matte,    ///< constant white
    Normal,   ///< (N + 1) / 2, world-space normal
    Position  ///< (P - bbox min) / bbox size, the active voxels' world bounding box
};

/// How the image is formed.
enum class Method
{
    Splat,           ///< EWA volume splatting (the renderer)
    RayMarch,        ///< reference integrator: ray-march the field (trilinear), a shadow ray per sample
    RayMarchGaussian, ///< diagnostic: ray-march the splatter's Gaussian reconstruction, shadows per kernel
    PathTrace         ///< reference: paths through the field (delta tracking), light scattered many times
};

/// The medium's optical model (vdb_render's names and defaults).
struct Medium
{
    Vec3d absorb{0.1, 0.1, 0.1};      ///< absorption per unit density per voxel length, RGB
    Vec3d scatter{1.5, 1.5, 1.5};     ///< scattering per unit density per voxel length, RGB
    Vec3d emission{0.0, 0.0, 0.0};    ///< self-emission R,G,B per unit density per voxel length (radiance
                                      ///< per unit optical length, like scatter x light colour); 0 = none

    /// Extinction sigma_t = absorb + scatter: optical depth per unit density per voxel length, RGB.
    Vec3d extinction() const { return absorb + scatter; }
};

/// How light scatters (docs/lighting.md#scattering): the Henyey-Greenstein phase function and
/// multiple scattering by octaves (Wrenninge, Kulla and Lundqvist, "Oz: The Great and
/// Volumetric", SIGGRAPH 2013): octave i scatters the lights again with the scattering scaled by
/// octaveScatter^i, the lights' optical depth by octaveExtinction^i and the anisotropy by
/// octaveAnisotropy^i, all read from the same light maps. The defaults are vdb_render's model:
/// isotropic, single scattering.
struct Scattering
{
    /// Henyey-Greenstein g, in (-1, 1): > 0 scatters forwards (a back-lit edge glows), 0 isotropic.
    double anisotropy = 0.0;
    /// Octaves, in [1, 16]: 1 is single scattering.
    int octaves = 1;
    double octaveScatter = 0.5;    ///< a, in [0, 1]: each octave's scattering relative to the one before
    double octaveExtinction = 0.8; ///< b, in [0, 1]: each octave's light optical depth relative to the one before
    double octaveAnisotropy = 0.7; ///< c, in [0, 1]: each octave's anisotropy relative to the one before
};

/// One directional light.
struct Light
{
    Vec3d direction{0.3, 0.3, 0.0};   ///< direction *towards* the light, world space (normalised)
    Vec3d color{0.7, 0.7, 0.7};       ///< radiance of the directional light, RGB

    /// The direction as a unit vector, for any finite non-zero length (1e-300 or 1e300 alike:
    /// scaled by its largest component before it is squared).
    Vec3d unitDirection() const
    {
        const double m = glm::max(glm::abs(direction.x), glm::max(glm::abs(direction.y), glm::abs(direction.z)));
        return glm::normalize(direction / m);
    }
};

/// A point or spot light (--point-light, --spot-light): light from one world point, falling off
/// as I / (r^2 + R^2) at distance r and shadowed by the volume; inside it too (an explosion's
/// core). Fog volumes and their --iso surfaces take it; level sets do not
/// (docs/lighting.md#point-and-spot-lights).
struct PointLight
{
    Vec3d position{0.0, 0.0, 0.0};   ///< world position
    Vec3d color{1.0, 1.0, 1.0};      ///< intensity I, R,G,B: about the radiance it gives at one world unit
    /// R, world units: the bulb's size, at least half a voxel length; within it the light stops
    /// growing, so that it stays finite at its own position.
    double radius = 0.0;
    /// A spot light's full cone angle in degrees, in (0, 180]; 0: a point light, every direction.
    double spotAngle = 0.0;
    Vec3d spotTarget{0.0, 0.0, -1.0}; ///< the world point a spot light aims at (not its position)
    /// The fraction of the cone's edge over which a spot light fades out (smoothstep in the
    /// cosine), in [0, 1]; Blender's Spot Blend, same default.
    double spotBlend = 0.15;
};

/// Emission from grids of the file besides the density (GridSource::withEmissionGrid,
/// withTemperatureGrid; a pyro cache's flame and temperature): radiance per voxel length
/// wherever they are, whatever the density (docs/equations.md#emission-grids).
struct GridEmission
{
    Vec3d color{1.0, 1.0, 1.0};   ///< emission grid: radiance R,G,B per voxel length per unit of its value
    double intensity = 1.0;       ///< emission grid: multiplies color
    double kelvinScale = 1.0;     ///< temperature grid: Kelvin = value x kelvinScale + kelvinOffset
    double kelvinOffset = 0.0;
    /// Blackbody radiance: luminance blackbodyIntensity x 1e-6 sigma T^4 / pi per voxel length
    /// (Blender's Principled Volume at Blackbody Intensity 1, per world unit there), colour of
    /// Planck's law seen by the CIE 1931 observer.
    double blackbodyIntensity = 1.0;
    /// Linear Rec.709 -> the space the other colours are in (the working space): the blackbody's
    /// colour is computed in Rec.709 and brought there. Identity: colours are linear Rec.709.
    Mat3d rec709ToWorking{1.0};
};

/// Most directional lights a render takes (RenderSettings::lights), and most point and spot
/// lights (RenderSettings::pointLights): each has a light map.
constexpr std::size_t kMaxLights = 64;
/// Most shutter layers (MotionBlur::layers) a pixel keeps.
constexpr int kMaxShutterLayers = 8;
/// Most sub-pixels a pixel side (SplatOptions::supersample): voxels a thirtieth of a pixel wide
/// span 1 sub-pixel at it.
constexpr int kMaxSupersample = 64;

/// Most worker threads a render takes (RenderSettings::threads): past the largest machines, and
/// a 2^31-thread arena fails in the thread library with no word of the option.
constexpr int kMaxThreads = 1024;

/// The lights' transmittance: shadow rays / light map.
struct ShadowOptions
{
    double step = 0.5;                ///< shadow-ray step in voxels (vdb_render's default is 3)
    double resolution = 1.0;          ///< light map: shadow rays every N voxel lengths across the light, bilinear
                                      ///< in between (docs/numerics.md#shading-per-slab-sample)
    double gain = 0.2;                ///< shadow-ray extinction falls as 1/(1 + gain * s), s in voxels
};

/// EWA splatting knobs.
struct SplatOptions
{
    double kernelSigma = 0.5;   ///< reconstruction kernel std. deviation in voxels (Eq. 19, V = s^2 I)
    /// Quasi-interpolating kernel weights: voxel kernels weighted so that the Gaussian sum has the
    /// trilinear field's local second moment, with negative halo kernels at the support's faces
    /// (docs/numerics.md#quasi-interpolation); false: each kernel weighs its voxel's value. Presets: draft false.
    bool prefilter = true;
    double lowpass = 1.0;       ///< low-pass filter variance in pixels^2 (Eq. 33, V^h = lowpass I)
    AntiAliasing antiAliasing = AntiAliasing::Floor;
    double cutoffRadius = 3.0;  ///< footprint evaluated where r = d^T Q d < cutoffRadius^2 (in sigma)
    bool renormalize = true;    ///< divide by the mass kept inside the cut-off, 1 - exp(-c^2/2)
    /// Footprint edge: true = the Gaussian less its value at the cut-off, so that footprints fall
    /// to 0 at their edge (no step to alias as they move: draft's cut-off of 2 sigma ends in one
    /// of 13.5 % of the peak); false = truncated (the paper's, Sec. 7.1). Volume splats.
    bool taper = false;
    ExpEvaluation expEvaluation = ExpEvaluation::Incremental;
    bool doublePrecision = true; ///< world -> camera transform and covariances in double (false: float)
    double slab = 2.0;          ///< image-aligned slab thickness in voxel lengths
    int tileKernelSpacing = 4;  ///< largest kernel spacing (voxels) used to model active tiles
    /// Where voxels span n pixels or more and the field varies, voxel kernels on a lattice n
    /// times finer: the trilinear field sampled every 1/n voxel, kernels of std. deviation
    /// kernelSigma / n (n^3 the kernels; 1 = off; docs/numerics.md#refined-kernels).
    int refine = 1;
    /// Emission and temperature grids where their light does not go as the density (light over
    /// density changes several-fold between neighbouring voxels) in optically thick density:
    /// sampled every 1/n voxel, n up to this as voxels span n pixels or more (2 at least; refine
    /// takes the emitters too; 1 = off; docs/lighting.md#emission-at-dense-hot-edges-and-refined-emitters).
    int refineEmission = 2;
    double lodPixels = 2.0;     ///< level of detail: merge blocks of 2^L voxels into one kernel where
                                ///< the block spacing projects to at most this many pixels, each
                                ///< voxel shared between two levels continuously with distance
                                ///< (level sets: one surface kernel a block and sheet, at a quarter
                                ///< of it); 0 = off
    double lodError = 0.05;     ///< level of detail: a block spanning more than a pixel merges only where
                                ///< the transmittance through any depth of it differs by at most this much
                                ///< between its columns (values smooth enough), in [0, 1]; 1 = by screen
                                ///< size alone
    /// Sub-pixel samples (docs/equations.md#sub-pixel-samples): where the voxels look smaller
    /// than supersampleSpan pixels, the fog volume's frame is composited at S x S sub-pixels a
    /// pixel over the pixels it covers and box-filtered down, S = ceil(supersampleSpan / voxel
    /// pixels) (the active voxels' median) up to this: a camera averages transmittance over the
    /// pixel where one footprint a pixel wide averages optical depth, which renders small
    /// volumes too opaque and too bright. 1 = off. Presets: draft 16, the others 32.
    int supersample = 32;
    /// How many sub-pixels a voxel should span (above): the finer, the closer to the camera's
    /// average; at 2 the image has converged as far as sub-pixels take it (1.4-pixel voxels
    /// render alike at 2, 3 and 4 sub-pixels a pixel). In [0.5, 16]. Presets: draft 1, the
    /// others 2.
    double supersampleSpan = 2.0;
    /// Image-space level of detail (docs/equations.md#image-space-level-of-detail): a fog
    /// footprint is accumulated at the coarsest of a screen tile's sample grids (every 2nd, 4th
    /// or 8th pixel) whose samples its narrowest standard deviation spans at least this many
    /// times, and reconstructed bilinearly onto the pixels when its slab is composited (the
    /// slab's sums are linear: only each footprint's interpolation error changes, at most
    /// 1/(4 n^2) of its peak). 0 = off (every footprint at every pixel); else in [1, 64].
    /// Presets: default 4 (footprints 8 pixels wide and more); draft, high and final 0 (draft is
    /// coarse by its larger pixels); with imageLodComposite it saves time
    /// (docs/performance.md#image-space-level-of-detail).
    double imageLod = 4.0;
    /// With imageLod: a screen tile whose footprints so far all lie at a coarser sample grid
    /// is also composited and lit there (the exact update, the light lookups and termination
    /// at every 2nd, 4th or 8th pixel), and its colour, transmittance and passes reconstructed
    /// bilinearly at the pixels when it is finished or a narrower footprint arrives
    /// (docs/equations.md#compositing-at-a-coarser-level). Frames with deep output, surfaces or
    /// shutter layers composite at every pixel. No effect while imageLod is 0. Presets: on
    /// (high and final: off, with imageLod).
    bool imageLodComposite = true;
    /// Larger pixels (docs/equations.md#larger-pixels): a fog volume whose voxels look large is
    /// splatted at one sample an n x n block of pixels (Blender's "Pixel Size"), its footprints
    /// convolved with the larger pixel's low-pass filter, and interpolated bilinearly back onto
    /// the pixels; n is the largest up to this at which the median voxel in view still spans
    /// supersampleSpan samples and that filter adds at most pixelSizeBlur of the kernel's own
    /// variance (n <= kernelSigma x voxel pixels x sqrt(pixelSizeBlur / (lowpass + 1/6)));
    /// volumes seen smaller keep every pixel. 1 = off; in [1, 16]. Presets: draft and default
    /// 4, high and final 1.
    int pixelSize = 4;
    /// With pixelSize: the variance the larger pixel's filter (its low-pass and the bilinear
    /// tent) may add to a voxel's footprint, as a share of the kernel's own: the finest detail
    /// at most sqrt(1 + this) wider. In (0, 1]. Presets: draft 1 (41 % wider; 2x2 pixels a
    /// sample from voxels of 4.3 pixels, 4x4 from 8.6), default 1/16 (3 % wider; 2x2 from 17.3
    /// pixels, 4x4 from 34.6).
    double pixelSizeBlur = 0.0625;
};

/// Surfaces (level-set grids, fog iso-surfaces; docs/equations.md#surface-kernels).
struct SurfaceOptions
{
    double isovalue = 0.0;      ///< iso-surface of a level set, world units (vdb_render -isovalue)
    SurfaceShader shader = SurfaceShader::Diffuse;
    double sigma = 0.55;        ///< surface kernel std. deviation in voxels (lattice steps under --lod) along the tangent plane
                                ///< (Sec. 6.4; wider than SplatOptions::kernelSigma so that no holes
                                ///< open between samples)
    double tolerance = 4.0;     ///< z-buffer depth tolerance in voxel lengths (lattice steps under --lod) (Sec. 7.2)
    /// Fog volumes: also render the iso-surface density == iso with flattened surface kernels
    /// composited with the volume's (Sec. 6.4); NaN = off.
    double iso = std::numeric_limits<double>::quiet_NaN();
    double isoOpacity = 1.0;    ///< opacity of that surface, in [0, 1]
};

/// How velocities are given (MotionBlur::unit).
enum class VelocityUnit
{
    Second, ///< world units per second (Houdini's v, Blender's velocity): a frame is 1/fps seconds
    Frame   ///< world units per frame
};

/// Motion blur from a velocity grid (GridSource::withVelocityGrid: attaching one turns it on):
/// every kernel moves linearly over the shutter, with the velocity at its centre
/// (docs/equations.md#motion-blur).
struct MotionBlur
{
    double velocityScale = 1.0;      ///< multiplies the velocities
    VelocityUnit unit = VelocityUnit::Second;
    double fps = 24.0;               ///< frames per second, for VelocityUnit::Second
    /// The shutter's open and close times in frames around the frame's time: a 180-degree
    /// shutter centred on the frame by default. close >= open; equal: no blur.
    double shutterOpen = -0.25, shutterClose = 0.25;
    /// Sub-frames over the shutter, each blurred over its 1/samples of it, averaged. Kernels
    /// widened by their paths blur optical depth; a camera averages images: an opaque edge
    /// moving over twice its width stays opaque where the shutter's average is half. More
    /// sub-frames converge to the shutter's average, at their cost in time
    /// (docs/equations.md#motion-blur); shutter layers (below) get most of the way in one sweep.
    /// 1: one frame; presets: draft and default 1, high 4, final 8.
    int samples = 1;
    /// A kernel whose path over its sub-frame is longer on the screen than this many of its
    /// standard deviations along it (the low-pass filter's included) is split into sub-kernels
    /// of at most that length: a Gaussian convolved with a box is then one Gaussian of the
    /// box's variance added to within 1.2 % (2), 4.6 % (3) or 11 % (4) of its peak
    /// (docs/equations.md#motion-blur). Presets: draft 4, default, high and final 2.
    double splitSigmas = 2.0;
    /// The light follows the material: each slab sample is lit where its material is in the
    /// still field (the optical depth's mean move subtracted; with shutter layers, each layer's
    /// own), as the reference carries each point's light along its path; false: lit by the
    /// still field's light where the material is now (the shutter's mid-time shadows): faster,
    /// but a rising fire is lit above its own shadow (docs/equations.md#motion-blur). Presets:
    /// draft false, the others true.
    bool lightFollows = true;
    /// Shutter layers: within each sub-frame, every pixel keeps this many transmittances, one
    /// per equal part of the sub-frame's shutter, and a sub-kernel adds its optical depth to
    /// the parts its piece of the path covers (kernels whose paths are not split: to all). So an
    /// opaque edge that moves across a pixel covers it for part of the shutter instead of all of
    /// it, as sub-frames would, at the cost of one sweep; a slab's colour is shared by its
    /// layers, each layer lit where its own material came from (lightFollows)
    /// (docs/equations.md#shutter-layers). 1: off. Presets: draft 1, default 3, high and final 1
    /// (their sub-frames converge).
    int layers = 3;

    /// Seconds (VelocityUnit::Second) or frames a velocity is multiplied by to move a point over
    /// the time from the frame's to @a frames frames later, scale included.
    double displacementPerVelocity(double frames) const
    {
        return velocityScale * frames / (unit == VelocityUnit::Second ? fps : 1.0);
    }
};

/// Everything a render needs besides the grid and the camera, in plain groups.
struct VDB_EWA_API RenderSettings
{
    Method method = Method::Splat;
    Medium medium;              ///< optical model
    Scattering scattering;      ///< phase function and multiple scattering (every volume's)
    /// Directional lights, each with its own shadow transmittance (a light map each): their
    /// scattered light adds. vdb_render's one light by default; empty: none.
    std::vector<Light> lights = std::vector<Light>(1);
    /// Constant ambient (sky) light, RGB radiance from every direction and never shadowed: each
    /// unit of scattering scatters it as it would the light (a fill for fog volumes; level sets
    /// and --iso surfaces ignore it). 0: none.
    Vec3d ambient{0.0, 0.0, 0.0};
    /// Point and spot lights, each shadowed through a light map of rays from its position and
    /// lit per slab sample as the directional lights are; empty: none.
    std::vector<PointLight> pointLights;
    GridEmission gridEmission;  ///< emission and temperature grids
    /// Colours that come from the grid and the shaders, not from these settings, are taken in
    /// the input space, as vdb_render writes them: the --color grid's values and the level-set
    /// shaders' (matte, normal, position, diffuse). This brings them to the space the other
    /// colours are in (the working space): the CLI sets it from --input-space; identity: they are
    /// in that space already. Negative components after it are taken as 0.
    Mat3d inputToWorking{1.0};
    ShadowOptions shadow;       ///< the lights' transmittance
    SplatOptions splat;         ///< EWA splatting knobs
    SurfaceOptions surface;     ///< level sets and fog iso-surfaces
    MotionBlur motionBlur;      ///< with the grid's velocity grid, if it has one
    /// Depth of field (CameraSettings::fstop): sub-frames, each through its own part of the lens
    /// (Camera::throughLensPart) and blurred by that part's circle of confusion, averaged: a
    /// camera averages images where widened kernels blur optical depth. With motion blur, sub-frame
    /// s takes part s of both the shutter and the lens, max(samples, lensSamples) of them
    /// (docs/equations.md#depth-of-field). 1: one frame; presets: draft 1, default 4, high 8, final 16.
    int lensSamples = 4;

    // --- Integration ---
    double cutoff = 0.005;            ///< density cutoff; rays stop where |T|^2 < cutoff (RGB T)
    double step = 1.0;                ///< primary-ray step in voxels (--method raymarch only)
    /// --method raymarch with motion blur or depth of field: rays per pixel, each at its own
    /// shutter time and lens point (stratified), averaged; more converge further.
    int blurSamples = 16;
    /// --method raymarch: rays per pixel, spread over the pixel's square (stratified, rotated per
    /// pixel: deterministic) and averaged, a box filter as a camera's pixel; with motion blur
    /// or depth of field the larger of it and blurSamples, each ray also at its own shutter time
    /// and lens point. 1: the pixel's centre ray (vdb_render's).
    int pixelSamples = 1;
    /// --method pathtrace: paths per pixel (--samples), spread over the pixel's square as
    /// pixelSamples' rays are, and averaged.
    int pathSamples = 64;
    /// --method pathtrace: scattering events after the first a path may have (Cycles' Volume
    /// Bounces): 0 is single scattering.
    int bounces = 16;

    // --- Execution ---
    /// Worker threads: N > 0 runs the render in its own tbb::task_arena of N threads; 0 runs it
    /// in the caller's arena (all cores, unless the host limits TBB). Never process-wide.
    int threads = 0;
    /// The volume rasteriser's SIMD backend where the CPU has one (AVX-512 or AVX2 with FMA,
    /// chosen at run time; within 1e-5 of the scalar one); false: the scalar backend, its test oracle
    /// (docs/architecture.md#simd-rasteriser).
    bool simd = true;
    /// Fog volumes: the streamed frame, which composites bricks front to back in depth windows
    /// and never builds the kernels of a brick hidden behind opaque screen tiles (within 1e-5
    /// of the whole frame); false: every kernel built, shaded and projected, the streamed
    /// frame's test oracle (docs/architecture.md#the-streamed-frame).
    bool cull = true;
    /// Memory budget of one frame's arrays in bytes (kernels, splats, bins, the light map, the
    /// frame), checked against the counts known before they are allocated (BudgetError);
    /// 0 = three quarters of the physical memory (docs/numerics.md#memory-budget).
    double maxMemory = 0.0;

    /// Throw ValueError naming the first setting out of range.
    void validate() const;

    /// Settings of a quality preset (the optical model and threads keep their defaults).
    static RenderSettings preset(Quality quality);
};

} // namespace vdb_ewa
