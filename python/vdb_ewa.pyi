"""Type stub of the vdb_ewa extension module (written by python/make_stub.py; do not edit)."""
import builtins
from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

Number = Union[int, float]
OptionValue = Union[str, Number, bool, Sequence[Number], Sequence[Sequence[Number]], None]

class Error(RuntimeError): ...
class IoError(Error, OSError): ...
class InputError(Error): ...
class ValueError(Error, builtins.ValueError): ...
class BudgetError(Error, MemoryError): ...
class Cancelled(Error): ...
class RenderWarning(UserWarning): ...

class Grid:
    """A scalar volume to render: a fog volume or a level set, from a .vdb file (vdb_ewa.open) or a numpy array (vdb_ewa.from_array)."""
    @property
    def name(self) -> str: ...
    @property
    def path(self) -> str: ...
    @property
    def stored_type(self) -> str: ...
    @property
    def is_level_set(self) -> bool: ...
    @property
    def active_voxel_count(self) -> int: ...
    @property
    def active_tile_count(self) -> int: ...
    @property
    def world_centre(self) -> Tuple[float, float, float]: ...
    @property
    def voxel_length(self) -> float: ...
    def transformed(self, object_to_world: npt.ArrayLike) -> "Grid": ...
    def with_added_volume(self, other: "Grid") -> "Grid": ...
    def with_velocity_grid(self, name: str) -> "Grid": ...

class CancelToken:
    """Cancels a render from any thread: pass it as render(..., cancel=token), call token.cancel()."""
    def __init__(self) -> None: ...
    def cancel(self) -> None: ...
    def reset(self) -> None: ...
    @property
    def cancelled(self) -> bool: ...

class Frame:
    """A rendered frame. Arrays are read-only float32 views in output_space, as the EXR holds them (at float precision: exr_type only affects write())."""
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def beauty(self) -> npt.NDArray[np.float32]: ...
    @property
    def aovs(self) -> Dict[str, npt.NDArray[np.float32]]: ...
    def aov(self, name: str) -> npt.NDArray[np.float32]: ...
    @property
    def stats(self) -> Dict[str, Any]: ...
    @property
    def coarse(self) -> bool: ...
    @property
    def warnings(self) -> List[str]: ...
    @property
    def render_seconds(self) -> float: ...
    @property
    def metadata(self) -> Dict[str, str]: ...
    def write(self, path: Union[str, PathLike]) -> None: ...

class Scene:
    """A grid that stays loaded, rendered from camera after camera (a viewport, a turntable): Scene(grid, **options)
takes a Grid or a path and render()'s keywords; render(**options) overrides them for one render. What
the renders can share they share (today the light maps, with the rays marched: Frame.stats says
light_maps_reused and light_rays_reused); each frame is the frame render() makes with the same
keywords, bit for bit (docs/api.md#scenes-what-a-render-reuses). One render at a time per scene."""
    def __init__(self, grid: Union[Grid, str, PathLike], **options: Any) -> None: ...
    def render(self, *, progress: Optional[Callable[[int], Optional[bool]]] = None, cancel: Optional[CancelToken] = None,
               progressive: Optional[Callable[["Frame"], Optional[bool]]] = None, **options: Any) -> Frame: ...
    def clear(self) -> None: ...
    @property
    def options(self) -> Dict[str, Any]: ...

def open(path: Union[str, PathLike], name: str = "") -> Grid: ...
def set_exr_threads(threads: int = 0) -> None: ...
def from_array(array: npt.ArrayLike, index_to_world: Optional[npt.ArrayLike] = None, name: str = "density", *,
               emission: Optional[npt.ArrayLike] = None, temperature: Optional[npt.ArrayLike] = None,
               velocity: Optional[npt.ArrayLike] = None) -> Grid: ...
def render(grid: Union[Grid, str, PathLike], *, progress: Optional[Callable[[int], Optional[bool]]] = None,
           cancel: Optional[CancelToken] = None,
           name: OptionValue = None,
           density_grid: OptionValue = None,
           camera_file: OptionValue = None,
           res: OptionValue = None,
           translate: OptionValue = None,
           rotate: OptionValue = None,
           lookat: OptionValue = None,
           up: OptionValue = None,
           camera: OptionValue = None,
           fov: Optional[Number] = None,
           focal: Optional[Number] = None,
           aperture: Optional[Number] = None,
           frame: Optional[Number] = None,
           fstop: Optional[Number] = None,
           focus_distance: Optional[Number] = None,
           near: Optional[Number] = None,
           far: Optional[Number] = None,
           absorb: OptionValue = None,
           scatter: OptionValue = None,
           light: OptionValue = None,
           point_light: OptionValue = None,
           spot_light: OptionValue = None,
           point_light_radius: Optional[Number] = None,
           emission: OptionValue = None,
           ambient: OptionValue = None,
           environment: OptionValue = None,
           environment_lights: Optional[int] = None,
           environment_intensity: Optional[Number] = None,
           anisotropy: Optional[Number] = None,
           multiple_scattering: Optional[int] = None,
           octave_scatter: Optional[Number] = None,
           octave_extinction: Optional[Number] = None,
           octave_anisotropy: Optional[Number] = None,
           bounces: Optional[int] = None,
           gain: Optional[Number] = None,
           cutoff: Optional[Number] = None,
           shadowstep: Optional[Number] = None,
           shadow_res: Optional[Number] = None,
           step: Optional[Number] = None,
           method: OptionValue = None,
           kernel_sigma: Optional[Number] = None,
           surface_sigma: Optional[Number] = None,
           lowpass: Optional[Number] = None,
           aa: OptionValue = None,
           cutoff_radius: Optional[Number] = None,
           slab: Optional[Number] = None,
           quality: OptionValue = None,
           exp: OptionValue = None,
           prefilter: OptionValue = None,
           renormalize: OptionValue = None,
           taper: OptionValue = None,
           precision: OptionValue = None,
           tile_spacing: Optional[int] = None,
           refine: Optional[int] = None,
           refine_emission: Optional[int] = None,
           lod: Optional[Number] = None,
           lod_error: Optional[Number] = None,
           image_lod: OptionValue = None,
           image_lod_composite: OptionValue = None,
           pixel_size: Optional[int] = None,
           pixel_size_blur: Optional[Number] = None,
           supersample: Optional[int] = None,
           supersample_span: Optional[Number] = None,
           iso: Optional[Number] = None,
           iso_opacity: Optional[Number] = None,
           isovalue: Optional[Number] = None,
           shader: OptionValue = None,
           color: OptionValue = None,
           emission_grid: OptionValue = None,
           emission_color: OptionValue = None,
           emission_intensity: Optional[Number] = None,
           temperature: OptionValue = None,
           temperature_scale: Optional[Number] = None,
           temperature_offset: Optional[Number] = None,
           blackbody_intensity: Optional[Number] = None,
           add_volume: OptionValue = None,
           add_volume_transform: OptionValue = None,
           add_volume_material: OptionValue = None,
           velocity_grid: OptionValue = None,
           velocity_scale: Optional[Number] = None,
           velocity_unit: OptionValue = None,
           fps: Optional[Number] = None,
           shutter: OptionValue = None,
           motion_samples: Optional[int] = None,
           motion_split: Optional[Number] = None,
           motion_layers: Optional[int] = None,
           motion_light: OptionValue = None,
           lens_samples: Optional[int] = None,
           blur_samples: Optional[int] = None,
           pixel_samples: Optional[int] = None,
           samples: Optional[int] = None,
           threads: Optional[int] = None,
           cpus: Optional[int] = None,
           simd: OptionValue = None,
           cull: OptionValue = None,
           max_memory: OptionValue = None,
           ocio_config: OptionValue = None,
           input_space: OptionValue = None,
           working_space: OptionValue = None,
           output_space: OptionValue = None,
           preview: OptionValue = None,
           display: OptionValue = None,
           view: OptionValue = None,
           exr_type: OptionValue = None,
           compression: OptionValue = None,
           zip_level: Optional[int] = None,
           aov: OptionValue = None,
           deep: Optional[bool] = None,
           ) -> Frame:
    """Render a grid as `vdb_ewa render` would; the keywords are its options (help(vdb_ewa.render)):

    name (--name): grid to render, as the density of a fog volume or a level set; --density-grid is the
        same option under the name a pyro cache's user looks for (default: the first scalar float or
        double grid, as vdb_render)
    density_grid (--density-grid): grid to render, as the density of a fog volume or a level set;
        --density-grid is the same option under the name a pyro cache's user looks for (default: the
        first scalar float or double grid, as vdb_render)
    camera_file (--camera-file): take the camera from a file: an .exr rendered by vdb_ewa (the same
        camera exactly) or by another renderer (its worldToCamera), or a .json of camera options or a
        worldToCamera matrix (docs/output.md); the camera options given here override its values
    res (--res): image size in pixels, WxH, each in [1, 65536] and at most 2^27 pixels in all
        (16384x8192) (default: 1920x1080)
    translate (--translate): camera position X,Y,Z in world units (default: 0,0,0)
    rotate (--rotate): camera rotation X,Y,Z in degrees, applied about x, then y, then z (default: look
        at the centre of the grid's active voxels)
    lookat (--lookat): aim the camera at the world point X,Y,Z
    up (--up): world vector that points up after --lookat (default: 0,1,0)
    camera (--camera): camera type: persp[ective] or ortho[graphic] (default: perspective)
    fov (--fov): horizontal field of view in degrees, in (0, 179) (default: 44.7966, from --focal and
        --aperture)
    focal (--focal): perspective focal length in mm, > 0 (default: 50)
    aperture (--aperture): perspective frame width in mm, > 0 (default: 41.2136)
    frame (--frame): orthographic frame width in world units, > 0 (default: 1)
    fstop (--fstop): depth of field: the thin lens's f-number, in [0, 1e6]; the lens is --focal / fstop
        wide, world units taken as metres (Houdini's and Blender's); 0: a pinhole, no depth of field;
        perspective cameras (default: 0)
    focus_distance (--focus-distance): depth of field: the depth in focus, world units along the view
        axis, > 0 (default: the depth of the point looked at, --lookat or the grid's centre)
    near (--near): near plane depth in world units, > 0 (default: 0.001)
    far (--far): far plane depth in world units, > --near; inf: none (default: 3.40282e+38)
    absorb (--absorb): absorption R,G,B per unit density per voxel length, each in [0, 1e6] (default:
        0.1,0.1,0.1)
    scatter (--scatter): scattering R,G,B per unit density per voxel length, each in [0, 1e6] (default:
        1.5,1.5,1.5)
    light (--light): directional light: direction towards it X,Y,Z (any non-zero length)[,R,G,B] with
        optional colour, each in [0, 1e6]; repeat for more lights (at most 64), each with its own
        shadows; their light adds (default: one, 0.3,0.3,0,0.7,0.7,0.7)
    point_light (--point-light): point light at world X,Y,Z (each within 1e12)[,R,G,B]: intensity R,G,B
        (the radiance it gives at one world unit; falls off as 1/(distance^2 + radius^2)), each in [0,
        1e12]; inside the volume too; shadowed through a light map of rays from it; repeat for more (at
        most 64); fog volumes and --iso surfaces (default: none; intensity 1,1,1)
    spot_light (--spot-light): spot light at world X,Y,Z aimed at TX,TY,TZ, full cone ANGLE in degrees
        in (0, 180][,BLEND,R,G,B]: BLEND the fraction of the cone's edge that fades, in [0, 1] (default
        0.15, Blender's), intensity as --point-light; repeat for more (default: none)
    point_light_radius (--point-light-radius): world units: nearer than this (and than half a voxel) a
        point or spot light grows no brighter, in [0, 1e12] (default: 0)
    emission (--emission): self-emission R,G,B per unit density per voxel length, each in [0, 1e6],
        added to the scattered light (default: 0,0,0)
    ambient (--ambient): constant ambient (sky) light R,G,B, never shadowed, scattered like --light: a
        fill for fog volumes; each in [0, 1e6], in --input-space (default: 0,0,0)
    environment (--environment): latitude-longitude environment image (.exr, .hdr; OpenEXR's and USD's
        orientation: +Y up, its centre facing +Z), RGB radiance in --input-space: a low-order, shadowed
        fill, added to --light as --environment-lights directional lights (default: none)
    environment_lights (--environment-lights): lights the environment becomes, each from the part of the
        sphere nearest its direction, in [1, 64] (default: 16)
    environment_intensity (--environment-intensity): multiplies the environment's radiance, >= 0
        (default: 1)
    anisotropy (--anisotropy): Henyey-Greenstein phase function's g for every light but --ambient, in
        (-1, 1): > 0 scatters forwards, so a back-lit edge glows (water droplets 0.6-0.9), 0 isotropic,
        vdb_render's (docs/lighting.md#scattering) (default: 0)
    multiple_scattering (--multiple-scattering): octaves of multiple scattering, in [1, 16]: octave i
        scatters each light again with --octave-scatter^i of the scattering, --octave-extinction^i of
        its optical depth and --octave-anisotropy^i of the anisotropy, from the same light maps: the
        soft, bright body light scattered many times gives a cloud; 1 single scattering, vdb_render's
        (docs/lighting.md#multiple-scattering) (default: 1)
    octave_scatter (--octave-scatter): each octave's scattering relative to the one before, in [0, 1]
        (default: 0.5)
    octave_extinction (--octave-extinction): each octave's light optical depth relative to the one
        before, in [0, 1] (default: 0.8)
    octave_anisotropy (--octave-anisotropy): each octave's anisotropy relative to the one before, in [0,
        1] (default: 0.7)
    bounces (--bounces): --method pathtrace: scattering events after the first a path may have (Cycles'
        Volume Bounces), in [0, 1024]; 0 single scattering (default: 16)
    gain (--gain): shadow-ray extinction falls as 1/(1 + gain * distance in voxels), finite and >= 0
        (default: 0.2)
    cutoff (--cutoff): density cutoff, and rays stop where |transmittance RGB|^2 < cutoff; range [0, 1)
        (default: 0.005)
    shadowstep (--shadowstep): shadow-ray step in voxels, >= 0.001; the light map's budget may raise it
        (docs/numerics.md) (default: 0.5)
    shadow_res (--shadow-res): light map: shadow rays every N voxels across the light, interpolated in
        between; range [0.25, 16] (default: 1)
    step (--step): primary-ray step in voxels for --method raymarch, >= 0.001 (default: 1); the splatter
        has no primary rays and ignores it
    method (--method): splat (EWA volume splatting), raymarch (the reference: ray-marches the trilinear
        field with a shadow ray per sample, as vdb_render; slow) or raymarch-gaussian (diagnostic: ray-
        marches the splatter's own Gaussian reconstruction and per-kernel shadows) or pathtrace (the
        truth of multiple scattering: --samples paths per pixel through the trilinear field, each
        scattering up to --bounces more times, physical shadows (--gain 0); slowest) (default: splat)
    kernel_sigma (--kernel-sigma): reconstruction kernel std. deviation in voxels, range [0.1, 4]
        (default: 0.5)
    surface_sigma (--surface-sigma): level sets and --iso: surface kernel std. deviation along the
        surface in voxels, range [0.1, 4] (default: 0.55)
    lowpass (--lowpass): screen-space low-pass filter variance in pixels^2, range [0, 100], > 0 unless
        --aa none (default: 1)
    aa (--aa): anti-aliasing: floor (each footprint axis at least --lowpass wide), ewa (resampling
        filter, Eq. 33: always adds --lowpass), swan (uniform scaling) or none (default: floor)
    cutoff_radius (--cutoff-radius): footprint cut-off radius in std. deviations, range [1, 6] (default:
        3)
    slab (--slab): image-aligned slab thickness in voxel lengths, range [0.05, 10000]; no thinner than
        --lod/16 pixel widths (--supersample-span/16 at --lod 0) at the nearest active voxel (default:
        2)
    quality (--quality): preset of the speed/accuracy knobs: draft, default, high or final (refined
        kernels); explicit options override it (values in docs/performance.md) (default: default)
    exp (--exp): footprint exp(-r/2): incremental (forward differencing), exact or table (default:
        incremental)
    prefilter (--prefilter): on: quasi-interpolating kernel weights (the Gaussian sum keeps the
        trilinear field's sharpness; negative halo kernels at its faces); off: each kernel weighs its
        voxel's value, softer and cheaper (default: on, draft off)
    renormalize (--renormalize): on: divide footprints by the mass kept inside --cutoff-radius; off:
        keep the truncated mass (default: on)
    taper (--taper): on: footprints are the Gaussian less its value at --cutoff-radius, falling to 0 at
        their edge (no step to flicker as they move); off: truncated (default: off, draft on)
    precision (--precision): world-to-camera transform and covariances in double or float (default:
        double)
    tile_spacing (--tile-spacing): largest kernel spacing in voxels for active tiles seen large, 1 to
        voxelise them; seen small a tile's spacing follows --lod pixels (--supersample-span at --lod 0)
        up to the tile's own size, between two spacings continuously with distance
        (docs/equations.md#active-tiles-seen-small) (default: 4, draft 8, high 2)
    refine (--refine): where voxels span N pixels or more, their kernels on a lattice N times finer: the
        trilinear field sampled every 1/N voxel (emission and temperature grids too), kernels N times
        narrower, N^3 as many; range [1, 4], 1 = off (default: 1)
    refine_emission (--refine-emission): emission and temperature grids where their light does not go as
        the density (light over density changes several-fold between neighbouring voxels) in optically
        thick density: the light sampled every 1/n voxel, n up to N as the voxels span n pixels or more
        (2 at least); --refine refines the emitters too; range [1, 4], 1 = off (default: 2; draft 1,
        high and final 4)
    lod (--lod): level of detail, pixels in [0, 64]: fog volumes: blocks of 2, 4 or 8 voxels a side
        become one kernel where the block projects to at most this many pixels, each voxel shared
        between two block sizes continuously with distance (no popping); level sets: one surface kernel
        a 2^3 or 4^3 block of voxels (for each sheet through it) where the block projects to at most a
        quarter as many; active tiles seen small: their kernels this many pixels apart (--tile-spacing);
        0 = off (tiles: --supersample-span pixels) (default: 2)
    lod_error (--lod-error): level of detail, fog volumes: a block wider than a pixel merges only where
        its values are smooth: the transmittance through any depth of it differs by at most this much
        between its columns; range [0, 1], 1 = by screen size alone (default: 0.05, draft 0.25)
    image_lod (--image-lod): image-space level of detail, samples, off or in [1, 64]: fog volumes: a
        footprint is accumulated at every 2nd, 4th or 8th pixel of its screen tile, the coarsest whose
        spacing its narrowest standard deviation spans at least this many times, and interpolated
        bilinearly onto the pixels when its slab is composited (at most 1/(4 n^2) of a footprint's peak
        off; docs/equations.md#image-space-level-of-detail); wide footprints (voxels seen large, a
        camera inside the volume) cost a third to a 16th of the samples, and with --image-lod-composite
        of the composites (docs/performance.md#image-space-level-of-detail); off = every footprint at
        every pixel (default: 4; draft, high and final off)
    image_lod_composite (--image-lod-composite): on: with --image-lod, a screen tile whose footprints so
        far all lie at a coarser sample grid is also lit and composited there (the light lookups, the
        exact update and termination at every 2nd, 4th or 8th pixel), and its colour, transmittance and
        passes interpolated bilinearly onto the pixels when it is finished or a narrower footprint
        arrives (docs/equations.md#compositing-at-a-coarser-level); frames with deep output, --iso
        surfaces or shutter layers composite at every pixel; off: every tile composited at its pixels
        (default: on, high and final off; no effect while --image-lod is off)
    pixel_size (--pixel-size): larger pixels, whole pixels in [1, 16]: a fog volume whose voxels look
        large is splatted at one sample an n x n block of pixels and interpolated bilinearly back onto
        the pixels (footprints filtered at the larger pixel: blurrier, never aliased; Z from the nearest
        larger pixel), n the largest up to this at which the median voxel in view still spans
        --supersample-span samples and the larger pixel's filter adds at most --pixel-size-blur of the
        kernel's variance, the next size's frame fading in near it (no jump as a camera moves;
        docs/equations.md#larger-pixels); volumes seen smaller, level sets, --iso surfaces and deep
        images keep every pixel; 1 = off (default: 4, draft 4, high and final 1)
    pixel_size_blur (--pixel-size-blur): with --pixel-size: the variance the larger pixel's filter (its
        low-pass and the bilinear tent) may add to a voxel's footprint, as a share of the kernel's own,
        in (0, 1]: n <= --kernel-sigma x the voxel's pixels x sqrt(this / (--lowpass + 1/6)); the finest
        detail at most sqrt(1 + this) wider: at the defaults 3 % (2x2 pixels a sample from voxels of 17
        pixels, 4x4 from 35), draft 1: 41 % (from 4.3 and 8.6 pixels) (default: 0.0625, draft 1)
    supersample (--supersample): fog volumes: where the voxels look smaller than --supersample-span
        pixels, the pixels the volume covers are composited in S x S sub-pixels and averaged (a box
        filter, as a camera averages a pixel; one footprint a pixel wide averages optical depth instead,
        which renders small volumes too opaque and too bright: docs/equations.md#sub-pixel-samples), S =
        ceil(span / the median voxel's pixels, active tiles counting as their voxels) up to this; at
        most 16 images' sub-pixels (and half of --max-memory), and 32 kernels a pixel of tiles larger
        than a leaf node (their lattices follow the sub-pixels); up to S^2 times the compositing where
        it acts; range [1, 64], 1 = off (default: 32; draft 16)
    supersample_span (--supersample-span): fog volumes: sub-pixels a voxel should span, in [0.5, 16];
        larger converges further to a camera's average where voxels are small, at more sub-pixels; at 2
        images have converged as far as sub-pixels take them (default: 2; draft 1)
    iso (--iso): fog volumes: also render the iso-surface density = VALUE with flattened surface
        kernels, lit by --light and composited with the volume; finite, nan: off (default: off)
    iso_opacity (--iso-opacity): opacity of the --iso surface, 0..1 (default: 1)
    isovalue (--isovalue): level sets: iso-surface to render, in world units, finite (default: 0)
    shader (--shader): level sets: diffuse (|N.ray|, a light at the camera), matte (white), normal
        ((N+1)/2) or position (world position in the active bounding box) (default: diffuse)
    color (--color): name of a vec3s grid in the input file with material colours, sampled trilinearly:
        level sets multiply the shader by it, fog volumes the scattering albedo (and the --iso surface's
        colour) (default: white)
    emission_grid (--emission-grid): name of a float grid in the input file that emits light wherever it
        is, whatever the density (a pyro cache's flame): radiance --emission-color x --emission-
        intensity x value per voxel length (default: none)
    emission_color (--emission-color): colour R,G,B of --emission-grid, each in [0, 1e6], in --input-
        space (default: 1,1,1)
    emission_intensity (--emission-intensity): multiplies --emission-color, in [0, 1e6] (default: 1)
    temperature (--temperature): name of a float grid in the input file whose values are temperatures:
        blackbody emission of Planck's law (CIE 1931 colour, luminance --blackbody-intensity x 1e-6
        sigma T^4 / pi per voxel length, Blender's Principled Volume) wherever it is, whatever the
        density (default: none)
    temperature_scale (--temperature-scale): Kelvin per unit of --temperature's values: Kelvin = value x
        scale + offset (Blender: the node's Temperature; Houdini: T1 - T0), within 1e6 (default: 1)
    temperature_offset (--temperature-offset): Kelvin at value 0 (Houdini: T0), within 1e6 (default: 0)
    blackbody_intensity (--blackbody-intensity): multiplies the blackbody's radiance, in [0, 1e6]; 1 is
        physically based (default: 1)
    add_volume (--add-volume): another fog volume in the same frame, FILE[:GRID] (GRID: the first float
        grid by default): its density is added to the input's on the input's voxels (resampled
        trilinearly where its transform differs: name the finest volume first), so volumes that
        interpenetrate hide and shadow each other in one sweep; same optical model; with --velocity-
        grid, each moves with its own velocity grid of that name (none: it stands still); repeat for
        more (default: none)
    add_volume_transform (--add-volume-transform): the object-to-world transform of the --add-volume of
        the same rank (the first for the first): 16 numbers, a 4x4 matrix row by row, or its first 12
        (the last row 0,0,0,1); column vectors, world = M (x, y, z, 1), after the file's own index-to-
        world map, as a DCC object's transform moves its volume (its velocities turn with it); finite,
        affine and invertible; one for every --add-volume, or none (default: none, the identity)
    add_volume_material (--add-volume-material): the optical model of the --add-volume of the same rank,
        its own where they interpenetrate: KEY=VALUE words, absorb=R,G,B scatter=R,G,B emission=R,G,B
        (per unit of its density per voxel length, as --absorb, --scatter, --emission; one number: grey;
        what it does not name is the input's) and color=GRID emission-grid=GRID temperature=GRID (its
        file's grids, as --color, --emission-grid, --temperature); 'same': the input's model, colour and
        emission grids; one for every --add-volume, or none (default: none, every volume takes the
        input's)
    velocity_grid (--velocity-grid): motion blur: name of the velocity grid in the input file, a vec3s
        or vec3d grid (Houdini's v or vel) or the float grids NAME.x, NAME.y, NAME.z (Blender's); each
        kernel moves linearly over the shutter with the velocity at its centre; naming one turns motion
        blur on; each --add-volume file's grid of that name moves that volume (default: none)
    velocity_scale (--velocity-scale): motion blur: multiplies the velocities, within 1e6 (default: 1)
    velocity_unit (--velocity-unit): motion blur: second (world units per second, Houdini's and
        Blender's) or frame (world units per frame) (default: second)
    fps (--fps): motion blur: frames per second, for --velocity-unit second, in [0.001, 1e6] (default:
        24)
    shutter (--shutter): motion blur: shutter OPEN,CLOSE in frames around the frame's time, each within
        1000, CLOSE >= OPEN (default: -0.25,0.25, a 180-degree shutter centred on the frame)
    motion_samples (--motion-samples): motion blur: sub-frames over the shutter, each blurred over its
        part of it, averaged; widened kernels blur optical depth where a camera averages images, so
        opaque edges need more to converge (docs/equations.md#motion-blur); about N times the time;
        range [1, 1024] (default: 1; draft 1, high 4, final 8)
    motion_split (--motion-split): motion blur: a kernel whose path over its sub-frame is longer on the
        screen than this many of its standard deviations is split into sub-kernels of at most that
        length; smaller keeps the blur's box shape closer (a single kernel's blur within 1.2 % of its
        peak at 2, 4.6 % at 3, 11 % at 4) at the cost of more kernels; in [0.5, 64] (default: 2; draft
        4)
    motion_layers (--motion-layers): motion blur: transmittances each pixel keeps over each sub-frame,
        one per equal part of its shutter; a split kernel's pieces darken only their parts, so an opaque
        edge moving across a pixel covers it part of the shutter, as sub-frames would, in one sweep,
        each layer lit where its own material came from (--motion-light follow)
        (docs/equations.md#shutter-layers); 1: off; range [1, 8] (default: 3; draft 1, high and final 1)
    motion_light (--motion-light): motion blur: follow (each slab sample lit where its material was in
        the still field, each shutter layer where its own was, as the reference carries each point's
        light along its path) or still (lit by the still field's light where the material is now: the
        shutter's mid-time shadows, faster, but a rising fire is lit above its own shadow: pyro 4 dB and
        a Mantaflow fire 10 dB further from the reference at default) (default: follow; draft still)
    lens_samples (--lens-samples): depth of field: sub-frames, each through its own part of the lens
        (rings of sectors of equal area) and blurred by that part's circle of confusion, averaged;
        widened kernels blur optical depth where a camera averages images, so thick media need more to
        converge (docs/equations.md#depth-of-field); with motion blur, the larger of it and --motion-
        samples, each sub-frame a part of both; about N times the time; range [1, 1024] (default: 4;
        draft 1, high 8, final 16)
    blur_samples (--blur-samples): --method raymarch with motion blur or depth of field: rays per pixel,
        each at its own shutter time and lens point, averaged; range [1, 4096] (default: 16)
    pixel_samples (--pixel-samples): --method raymarch: rays per pixel, spread over the pixel's square
        (Halton points, rotated per pixel) and averaged: a box filter as a camera's pixel, the anti-
        aliased reference; with motion blur or depth of field the larger of it and --blur-samples, each
        ray also at its own time and lens point; range [1, 4096] (default: 1, the pixel's centre ray)
    samples (--samples): --method pathtrace: paths per pixel, spread over the pixel's square, in [1,
        1048576] (default: 64); level sets: vdb_render's rays per pixel, accepted for compatibility, the
        EWA filter anti-aliases without extra samples
    threads (--threads): worker threads, 0 = the CPUs the farm task or container was granted
        ($SLURM_CPUS_PER_TASK, the cgroup's quota), else all cores; range [0, 1024] (default: 0;
        docs/farm.md)
    cpus (--cpus): worker threads, 0 = the CPUs the farm task or container was granted
        ($SLURM_CPUS_PER_TASK, the cgroup's quota), else all cores; range [0, 1024] (default: 0;
        docs/farm.md)
    simd (--simd): on: the volume rasteriser uses the CPU's vector unit (AVX-512 or AVX2, detected at
        run time; images within 1e-5 of off); off: one pixel at a time, the reference it is tested
        against (default: on)
    cull (--cull): fog volumes: on: the streamed frame, bricks (leaf nodes, active tiles) composited
        front to back in depth windows, those behind opaque screen tiles never expanded into kernels,
        light marched where it is looked up (images within 1e-5 of off); off: every kernel built and
        projected and every light ray marched, the reference it is tested against (default: on;
        docs/architecture.md#the-streamed-frame)
    max_memory (--max-memory): memory budget of a frame in bytes, with an optional K, M, G or T suffix
        (powers of 1024), range [64M, 1e18]; a frame that would need more stops before allocating it
        (exit 5) (default: 0 = 3/4 of the memory the farm task or container was granted
        ($SLURM_MEM_PER_NODE, the cgroup's limit), else of the physical memory)
    ocio_config (--ocio-config): OpenColorIO config file (default: $OCIO, else vdb_ewa's shipped ACES
        config); an unusable config is a warning and falls back to the next
    input_space (--input-space): colour space of the colour values given on the command line and in job
        files (--light colour, --ambient, --absorb, --scatter, --emission): converted to the working
        space (default: lin_rec709, linear sRGB, what vdb_render's values mean)
    working_space (--working-space): colour space the render is computed in (default: the config's
        scene_linear role; ACEScg in the shipped config)
    output_space (--output-space): colour space of .exr and .hdr outputs (default: with vdb_ewa's
        shipped config, --input-space (lin_rec709), what vdb_render writes; with your own config ($OCIO
        or --ocio-config), its scene_linear role)
    preview (--preview): also write an 8-bit display-referred PNG of the beauty over black
    display (--display): display of 8-bit outputs (.png, .jpg, .tif, .ppm) and --preview (default: the
        config's default display)
    view (--view): view of 8-bit outputs and --preview (default: the display's default view; the shipped
        config's is Un-tone-mapped, the plain sRGB curve, and "ACES 1.0 - SDR Video" tone-maps)
    exr_type (--exr-type): pixel type of the colour channels: half or float; Z is always float (default:
        half)
    compression (--compression): EXR compression: none, rle, zip, zips, piz, dwaa or dwab; other formats
        ignore it (a warning); --deep files take none, rle or zips (default: zip, zips for --deep)
    zip_level (--zip-level): deflate level of zip and zips EXR compression, 1 (fastest) to 9 (smallest),
        zlib's scale (flat files are deflated by libdeflate): at 1 a 1080p frame (half colour, float Z)
        writes in about 0.8x the time of level 4, up to 30 % larger; range [1, 9] (default: 1)
    aov (--aov): extra passes as layer.R/G/B channels, comma-separated: transmittance, shadow, emission
        (alpha and Z are always written; definitions in docs/output.md)
    deep (--deep): write a deep scanline EXR: one sample per non-empty slab (R, G, B, A premultiplied,
        Z, ZBack; tidy)
    """
