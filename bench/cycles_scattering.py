#!/usr/bin/python3
"""Issue 56's yardstick: a fog sphere lit by a sun, Blender Cycles against vdb_ewa's CLI.

A sphere of uniform density 1 (radius --radius-voxels voxels, a one-voxel linear edge, world
radius 1), written by pyopenvdb, is rendered
- by Cycles in `blender -b -t 1` (a Volume object loading the file; Principled Volume of Density
  --density, Color --albedo, Absorption Color black, Anisotropy --anisotropy; a sun of strength
  --sun-strength towards --sun-dir, angle 0; a black world; transparent film; Volume Bounces
  --bounces; --samples per pixel, no adaptive sampling, no clamping, no denoiser, a 1-pixel box
  filter), twice, with seeds --seed and --seed + 1, to measure its own noise;
- by the vdb_ewa CLI from options derived by docs/blender.md's formulas: --light towards the sun,
  colour E / 4 pi; --scatter C D L and --absorb (1 - C) D L per voxel length L; --gain 0;
  --method raymarch with fine --step and --shadowstep and --pixel-samples (a box filter, as
  Cycles' here): single scattering, isotropic. Options after --vdb-ewa-args are appended,
  replacing this script's own of the same name (`--vdb-ewa-args --method pathtrace --bounces 16
  --samples 256`).
Blender places voxel (i, j, k) at the centre of the index cell [i, i + 1]^3, OpenVDB and
vdb_ewa at (i, j, k): Blender's file has its map moved back by half a voxel and vdb_ewa's not,
so the sphere's centre is the world origin in both.

It prints and saves (OUT/summary.json, OUT/summary.txt) the PSNR (peak 1) on RGB and on alpha
of the premultiplied images between vdb_ewa and the mean of Cycles' two seeds, Cycles'
seed-to-seed PSNR, the RMS noise of that mean (rms(a - b) / 2) and the PSNR that noise alone
allows, and the mean RGB inside the sphere's silhouette (vdb_ewa / Cycles, with the ratio's
standard error from Cycles' noise). --check-anisotropy G2 also renders Cycles at anisotropy G2
(two seeds) and reports its brightness against the main Cycles render; at --bounces 0 it
checks Cycles' phase convention pixel by pixel: single scattering from a sun at anisotropy g is
isotropic's times 4 pi p_HG(cos t) along each ray, cos t = L . d (L towards the sun, d the ray
from the eye; g > 0 forwards), against the mirrored convention cos t = -L . d.
OUT/compare.png: vdb_ewa | Cycles | the difference x 4 (red: vdb_ewa brighter) [| Cycles at G2],
sRGB over black (also vdb_ewa.png, cycles.png). The PSNR "within 0.95 of the radius" leaves out
the silhouette's edge ring, where vdb_ewa's 4 pixel samples alias against Cycles' 512.

Measured at the defaults (Blender 3.4.1, 128x128, D 2: optical depth 4 across, sun (1, 1, 0.3):
scattering angle 46 deg at the centre; the machine's 2 cores shared with compiles):
- Volume Bounces 0 against --method raymarch --gain 0: 61.1 dB RGB (Cycles' noise allows 66.4),
  64.8 dB within 0.95 of the radius (66.9), alpha 46.5 dB (53.3; 16 pixel samples bring the edge
  ring to its noise); mean ratio 1.0013 +- 0.0001, of which the shadow march's +0.20 %.
  Without Blender's half voxel (--no-half-voxel) the edge ring is off by 0.16 in alpha (RMS).
- Anisotropy 0.6 at Volume Bounces 0: 2.149 x the isotropic image's mean; pixel by pixel it is
  the isotropic image x 4 pi p_HG(L . d) (91.8 dB from the same seeds; the mirrored convention 18.3 dB).
- Volume Bounces 16: Cycles 3.0x the single-scattering image (ratio 0.333), 21.0 dB;
  64 bounces add 0.3 % +- 0.3 % more (64 samples).
- Times: Cycles 72-76 s a render at Bounces 0, 132-136 s at 16; vdb_ewa 96-107 s.

    /usr/bin/python3 bench/cycles_scattering.py --out /tmp/cs0 --bounces 0 --check-anisotropy 0.6
    /usr/bin/python3 bench/cycles_scattering.py --out /tmp/cs16              # 16 volume bounces
    /usr/bin/python3 bench/cycles_scattering.py --out /tmp/cs16 --vdb-ewa-args --method pathtrace ...

Cycles' images are kept in OUT, named by a hash of everything they depend on, and reused by a
later run with the same settings (--rerender to render them again), so vdb_ewa's options can be
iterated on without Blender. The same file runs inside Blender (`--python` this file `--
--blender-job JOB.json`). Needs Blender 3.4 (Debian's blender), and numpy, pyopenvdb and
OpenImageIO for /usr/bin/python3."""
import hashlib
import json
import math
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "blender"))
DEFAULT_CLI = "/tmp/build-pch/cmd/vdb_ewa/vdb_ewa"


# --------------------------------------------------------------------------------------------
# Inside Blender: build the scene once, render each job of the list, save float EXRs.
# --------------------------------------------------------------------------------------------
def blender_main(job_path):
    import bpy
    import mathutils

    job = json.load(open(job_path))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.render.resolution_x, scene.render.resolution_y = job["res"]
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = True
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 1
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.use_denoising = False
    cycles.use_adaptive_sampling = False  # a fixed sample count: seed-to-seed noise is the noise
    cycles.sample_clamp_direct = 0.0  # Cycles clamps indirect light at 10 by default
    cycles.sample_clamp_indirect = 0.0
    cycles.light_sampling_threshold = 0.0
    cycles.pixel_filter_type = "BOX"  # vdb_ewa's --pixel-samples: a box over the pixel
    cycles.filter_width = 1.0
    cycles.use_animated_seed = False
    cycles.volume_step_rate = job["step_rate"]
    cycles.volume_max_steps = job["max_steps"]

    world = bpy.data.worlds.new("black")
    world.use_nodes = False
    world.color = (0.0, 0.0, 0.0)
    scene.world = world

    volume = bpy.data.volumes.new("sphere")
    volume.filepath = job["vdb"]
    volume.render.precision = "FULL"  # Blender loads grids as half floats by default
    obj = bpy.data.objects.new("sphere", volume)
    scene.collection.objects.link(obj)
    from blender_materials import principled_volume  # the Blender tests' (tests/blender)
    material = principled_volume("fog", "density", job["density"], job["color"])
    principled = next(n for n in material.node_tree.nodes if n.type == "PRINCIPLED_VOLUME")
    volume.materials.append(material)

    camera_data = bpy.data.cameras.new("camera")
    camera_data.lens = job["focal"]
    camera_data.sensor_width = job["sensor"]
    camera_data.sensor_fit = "AUTO"
    camera_data.clip_start, camera_data.clip_end = job["clip"]
    camera = bpy.data.objects.new("camera", camera_data)
    scene.collection.objects.link(camera)
    eye = mathutils.Vector(job["eye"])
    camera.matrix_world = mathutils.Matrix.LocRotScale(eye, (-eye).to_track_quat("-Z", "Y"), None)
    scene.camera = camera

    sun_data = bpy.data.lights.new("sun", "SUN")
    sun_data.energy = job["sun_strength"]
    sun_data.color = (1.0, 1.0, 1.0)
    sun_data.angle = 0.0  # a directional light, as vdb_ewa's
    sun = bpy.data.objects.new("sun", sun_data)
    scene.collection.objects.link(sun)
    # Its local +Z towards the sun: it shines along its -Z.
    sun.matrix_world = mathutils.Matrix.LocRotScale(None, mathutils.Vector(job["sun_dir"]).to_track_quat("Z", "Y"), None)

    grid_names = []
    volume.grids.load()
    for grid in volume.grids:
        grid_names.append(grid.name)
    print("cycles_scattering: grids %s, matrix_object %s" % (grid_names, [list(r) for r in volume.grids[0].matrix_object]))

    for render in job["renders"]:
        principled.inputs["Anisotropy"].default_value = render["anisotropy"]
        cycles.volume_bounces = render["bounces"]
        cycles.max_bounces = max(1024, render["bounces"] + 1)  # never the limit
        cycles.diffuse_bounces = cycles.glossy_bounces = cycles.transmission_bounces = 0
        cycles.transparent_max_bounces = 8
        cycles.samples = render["samples"]
        cycles.seed = render["seed"]
        t0 = time.monotonic()
        bpy.ops.render.render()
        seconds = time.monotonic() - t0
        result = bpy.data.images["Render Result"]
        settings = scene.render.image_settings
        settings.file_format, settings.color_depth, settings.color_mode = "OPEN_EXR", "32", "RGBA"
        settings.exr_codec = "ZIP"
        result.save_render(render["exr"])
        with open(render["exr"] + ".json", "w") as f:
            json.dump(dict(render, seconds=seconds, blender=bpy.app.version_string), f)
        print("cycles_scattering: rendered %s in %.1f s" % (os.path.basename(render["exr"]), seconds), flush=True)


# --------------------------------------------------------------------------------------------
# The driver (/usr/bin/python3).
# --------------------------------------------------------------------------------------------
def parse_vector(text, n=3):
    values = [float(v) for v in text.split(",")]
    if len(values) != n:
        raise SystemExit("expected %d comma-separated numbers: %s" % (n, text))
    return values


def main():
    import argparse
    import numpy as np

    argv = sys.argv[1:]
    extra = []
    if "--vdb-ewa-args" in argv:
        i = argv.index("--vdb-ewa-args")
        argv, extra = argv[:i], argv[i + 1:]
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="Options after --vdb-ewa-args go to the vdb_ewa CLI as they are, replacing this script's own of the same name.")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--cli", default=DEFAULT_CLI, help="the vdb_ewa CLI (default: %(default)s)")
    p.add_argument("--blender", default="blender")
    p.add_argument("--res", default="128x128", help="WxH (default: %(default)s)")
    p.add_argument("--radius-voxels", type=int, default=32, help="the sphere's radius in voxels (default: %(default)s)")
    p.add_argument("--density", type=float, default=2.0,
                   help="Principled Volume Density D, extinction per world unit; optical depth across the sphere 2 D (default: %(default)s)")
    p.add_argument("--albedo", type=float, default=1.0, help="Principled Volume Color, grey (default: %(default)s)")
    p.add_argument("--anisotropy", type=float, default=0.0, help="Cycles' Anisotropy g (default: %(default)s)")
    p.add_argument("--check-anisotropy", type=float, default=None, metavar="G2",
                   help="also render Cycles at anisotropy G2 and compare its brightness (at --bounces 0: its phase convention)")
    p.add_argument("--bounces", type=int, default=16, help="Cycles' Volume Bounces (default: %(default)s)")
    p.add_argument("--samples", type=int, default=512, help="Cycles' samples per pixel (default: %(default)s)")
    p.add_argument("--seed", type=int, default=1, help="Cycles' seeds are SEED and SEED + 1 (default: %(default)s)")
    p.add_argument("--step-rate", type=float, default=1.0, help="Cycles' volume_step_rate (default: %(default)s)")
    p.add_argument("--max-steps", type=int, default=1024, help="Cycles' volume_max_steps (default: %(default)s)")
    p.add_argument("--sun-dir", default="1,1,0.3",
                   help="towards the sun X,Y,Z (default: %(default)s: from the side and behind the sphere as the camera sees it)")
    p.add_argument("--sun-strength", type=float, default=4.0, help="sun strength E, W/m^2 (default: %(default)s)")
    p.add_argument("--eye", default="0,-4,0", help="camera position, looking at the origin, +Z up (default: %(default)s)")
    p.add_argument("--focal", type=float, default=50.0, help="focal length, mm (default: %(default)s)")
    p.add_argument("--sensor", type=float, default=36.0, help="sensor width, mm, Auto fit (default: %(default)s)")
    p.add_argument("--step", type=float, default=1.0,
                   help="vdb_ewa raymarch --step, voxels (default: %(default)s; 0.25 changes the mean by 0.02 %%)")
    p.add_argument("--shadowstep", type=float, default=0.0625,
                   help="vdb_ewa --shadowstep, voxels: vdb_render's shadow ray drops h/2 of depth on average, "
                        "+(exp(sigma_t h / 2) - 1) brighter (default: %(default)s)")
    p.add_argument("--pixel-samples", type=int, default=4, help="vdb_ewa raymarch --pixel-samples (default: %(default)s)")
    p.add_argument("--rerender", action="store_true", help="render Cycles again even where its images are kept")
    p.add_argument("--no-half-voxel", action="store_true",
                   help="diagnostic: give vdb_ewa Blender's file as it is (without Blender's half-voxel placement)")
    args = p.parse_args(argv)

    import OpenImageIO as oiio
    import pyopenvdb

    os.makedirs(args.out, exist_ok=True)
    out = lambda name: os.path.join(os.path.abspath(args.out), name)
    width, height = (int(v) for v in args.res.split("x"))
    R = args.radius_voxels
    voxel = 1.0 / R
    sun_dir = np.array(parse_vector(args.sun_dir))
    sun_dir /= np.linalg.norm(sun_dir)
    eye = np.array(parse_vector(args.eye))
    color = [args.albedo] * 3

    # 1. The sphere: density 1 within R - 1/2 voxels of the index origin, 0 beyond R + 1/2, linear between.
    n = R + 2
    axis = np.arange(-n, n + 1, dtype=np.float64)
    r = np.sqrt(axis[:, None, None] ** 2 + axis[None, :, None] ** 2 + axis[None, None, :] ** 2)
    values = np.clip(R + 0.5 - r, 0.0, 1.0).astype(np.float32)

    def write_sphere(path, offset):
        grid = pyopenvdb.FloatGrid()
        grid.name = "density"
        grid.gridClass = pyopenvdb.GridClass.FOG_VOLUME
        grid.copyFromArray(values, ijk=(-n, -n, -n), tolerance=0.0)
        grid.transform = pyopenvdb.createLinearTransform([[voxel, 0, 0, 0], [0, voxel, 0, 0], [0, 0, voxel, 0],
                                                          [offset, offset, offset, 1.0]])
        pyopenvdb.write(path, grids=[grid])

    # Blender puts voxel (i, j, k) at index (i, j, k) + 1/2: its file's map is moved back by half a voxel.
    blender_vdb, ewa_vdb = out("sphere_blender.vdb"), out("sphere_vdb_ewa.vdb")
    write_sphere(blender_vdb, -0.5 * voxel)
    write_sphere(ewa_vdb, 0.0)
    if args.no_half_voxel:
        ewa_vdb = blender_vdb

    # 2. Cycles: the renders this run needs, kept by a hash of what they depend on.
    scene_key = dict(res=[width, height], radius_voxels=R, density=args.density, color=color, sun_dir=sun_dir.tolist(),
                     sun_strength=args.sun_strength, eye=eye.tolist(), focal=args.focal, sensor=args.sensor,
                     step_rate=args.step_rate, max_steps=args.max_steps, samples=args.samples, version=2)

    def cycles_render(anisotropy, seed):
        key = dict(scene_key, anisotropy=anisotropy, bounces=args.bounces, seed=seed)
        digest = hashlib.sha1(json.dumps(key, sort_keys=True).encode()).hexdigest()[:10]
        name = "cycles_g%g_b%d_s%d_%s.exr" % (anisotropy, args.bounces, seed, digest)
        return dict(anisotropy=anisotropy, bounces=args.bounces, seed=seed, samples=args.samples, exr=out(name))

    seeds = (args.seed, args.seed + 1)
    main_renders = [cycles_render(args.anisotropy, s) for s in seeds]
    check_renders = [cycles_render(args.check_anisotropy, s) for s in seeds] if args.check_anisotropy is not None else []
    todo = [r for r in main_renders + check_renders if args.rerender or not os.path.isfile(r["exr"] + ".json")]
    cycles_seconds = 0.0
    if todo:
        job = dict(scene_key, vdb=blender_vdb, color=color, clip=[0.1, 100.0], renders=todo)
        with open(out("blender_job.json"), "w") as f:
            json.dump(job, f, indent=1)
        command = [args.blender, "-b", "--factory-startup", "-t", "1", "--python-exit-code", "1",
                   "--python", os.path.abspath(__file__), "--", "--blender-job", out("blender_job.json")]
        print("$ " + " ".join(command), flush=True)
        t0 = time.monotonic()
        done = subprocess.run(command, capture_output=True, text=True)
        cycles_seconds = time.monotonic() - t0
        with open(out("blender.log"), "w") as f:
            f.write(done.stdout + done.stderr)
        if done.returncode != 0 or any(not os.path.isfile(r["exr"] + ".json") for r in todo):
            sys.exit("blender failed (%d); the log ends:\n%s" % (done.returncode, (done.stdout + done.stderr)[-3000:]))
        for line in done.stdout.splitlines():
            if line.startswith("cycles_scattering:"):
                print("  " + line)
    else:
        print("Cycles: reusing %s" % ", ".join(os.path.basename(r["exr"]) for r in main_renders + check_renders))
    render_seconds = {r["exr"]: json.load(open(r["exr"] + ".json"))["seconds"] for r in main_renders + check_renders}

    # 3. vdb_ewa: docs/blender.md's mapping.
    join = lambda v: ",".join("%.17g" % x for x in v)
    light = list(sun_dir) + [c * args.sun_strength / (4.0 * math.pi) for c in (1.0, 1.0, 1.0)]
    scatter = [c * args.density * voxel for c in color]
    absorb = [max(1.0 - c, 0.0) * 1.0 * args.density * voxel for c in color]  # Absorption Color black: (1 - sqrt 0) = 1
    horizontal = width >= height  # Auto sensor fit
    aperture = args.sensor if horizontal else args.sensor * width / height
    ewa_exr = out("vdb_ewa.exr")
    cli = [args.cli, ewa_vdb, ewa_exr, "--name", "density", "--res", "%dx%d" % (width, height), "--translate", join(eye),
           "--lookat", "0,0,0", "--up", "0,0,1", "--focal", "%.17g" % args.focal, "--aperture", "%.17g" % aperture,
           "--near", "0.1", "--far", "100", "--light", join(light), "--scatter", join(scatter), "--absorb", join(absorb),
           "--gain", "0", "--cutoff", "0", "--method", "raymarch", "--step", "%g" % args.step, "--shadowstep", "%g" % args.shadowstep,
           "--pixel-samples", str(args.pixel_samples), "--working-space", "lin_rec709", "--output-space", "lin_rec709",
           "--exr-type", "float", "-q"]
    cli = without_overridden(cli, extra) + extra
    print("$ " + " ".join(cli), flush=True)
    t0 = time.monotonic()
    done = subprocess.run(cli, capture_output=True, text=True)
    ewa_seconds = time.monotonic() - t0
    if done.returncode != 0:
        sys.exit("vdb_ewa failed (%d): %s" % (done.returncode, done.stderr))

    # 4. The comparison.
    def read_rgba(path):
        from driver_support import read_image  # the Blender tests' (tests/blender)
        pixels, names = read_image(path)
        return np.stack([pixels[..., names.index(c)] for c in "RGBA"], axis=-1).astype(np.float64)

    def psnr(a, b):
        mse = float(np.mean((a - b) ** 2))
        return math.inf if mse == 0.0 else 10.0 * math.log10(1.0 / mse)

    # Each pixel's centre ray (Blender's and vdb_ewa's pinhole; pixel centres at +1/2).
    forward = -eye / np.linalg.norm(eye)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    film_w = aperture
    film_h = aperture * height / width
    xs = ((np.arange(width) + 0.5) / width - 0.5) * film_w
    ys = (0.5 - (np.arange(height) + 0.5) / height) * film_h
    d = args.focal * forward[None, None, :] + xs[None, :, None] * right[None, None, :] + ys[:, None, None] * up[None, None, :]
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    closest = np.linalg.norm(np.cross(d, -eye[None, None, :]), axis=-1)  # the ray's distance from the centre
    mask = closest < 1.0  # the sphere's silhouette
    inner = closest < 0.95  # without its edge ring, where pixel sampling (aliasing) differs most
    cos_t = d @ sun_dir  # the scattering angle's cosine, L . d

    ewa = read_rgba(ewa_exr)
    ca, cb = read_rgba(main_renders[0]["exr"]), read_rgba(main_renders[1]["exr"])
    if ewa.shape != ca.shape:
        sys.exit("vdb_ewa's image is %s, Cycles' %s" % (ewa.shape, ca.shape))
    cyc = 0.5 * (ca + cb)

    def stats(a, b, mean_img):
        """Seed-to-seed numbers of two Cycles images a, b, their mean mean_img."""
        rms_noise_rgb = float(np.sqrt(np.mean((a[..., :3] - b[..., :3]) ** 2))) / 2.0
        rms_noise_a = float(np.sqrt(np.mean((a[..., 3] - b[..., 3]) ** 2))) / 2.0
        diff_mean = 0.5 * (a[..., :3] - b[..., :3])[mask].mean(axis=-1)  # each pixel's noise in the mean of R, G, B
        mean = mean_img[..., :3][mask].mean(axis=0)
        rms_inner = float(np.sqrt(np.mean((a[..., :3][inner] - b[..., :3][inner]) ** 2))) / 2.0
        return dict(seed_psnr_rgb=psnr(a[..., :3], b[..., :3]), seed_psnr_alpha=psnr(a[..., 3], b[..., 3]),
                    noise_psnr_rgb_inner=10 * math.log10(1 / rms_inner ** 2) if rms_inner else math.inf,
                    noise_rms_rgb=rms_noise_rgb, noise_rms_alpha=rms_noise_a,
                    noise_psnr_rgb=10 * math.log10(1 / rms_noise_rgb ** 2) if rms_noise_rgb else math.inf,
                    noise_psnr_alpha=10 * math.log10(1 / rms_noise_a ** 2) if rms_noise_a else math.inf,
                    mean_rgb=mean.tolist(), mean_stderr=float(diff_mean.std() / math.sqrt(mask.sum())))

    cstats = stats(ca, cb, cyc)
    ewa_mean = ewa[..., :3][mask].mean(axis=0)
    mse_rgb = float(np.mean((ewa[..., :3] - cyc[..., :3]) ** 2))
    bias_rgb = math.sqrt(max(mse_rgb - cstats["noise_rms_rgb"] ** 2, 0.0))  # the RMS difference that is not Cycles' noise
    ratio = (ewa_mean / np.array(cstats["mean_rgb"])).tolist()
    ratio_err = cstats["mean_stderr"] / float(np.mean(cstats["mean_rgb"]))
    summary = dict(
        settings=dict(vars(args), vdb_ewa_args=extra, voxel_size=voxel, optical_depth_across=2.0 * args.density,
                      sun_dir_unit=sun_dir.tolist(), light=light, scatter=scatter, absorb=absorb, aperture=aperture,
                      angle_sun_propagation_to_view_deg=math.degrees(math.acos(float(np.clip(-sun_dir @ forward, -1, 1)))),
                      scattering_angle_at_centre_deg=math.degrees(math.acos(float(np.clip(sun_dir @ forward, -1, 1)))),
                      silhouette_pixels=int(mask.sum()), inner_pixels=int(inner.sum()),
                      # vdb_render's shadow ray (lib/shading/shadow_transmittance.cpp) samples at k h, k >= 1, each
                      # weighing h: it drops h/2 of optical depth on average, so its light is this much too bright.
                      shadow_march_brightening=math.expm1(0.5 * args.shadowstep * (scatter[0] + absorb[0]))),
        commands=dict(vdb_ewa=cli),
        seconds=dict(cycles_blender_total=cycles_seconds, cycles_each={os.path.basename(k): v for k, v in render_seconds.items()},
                     vdb_ewa=ewa_seconds),
        cycles=cstats,
        vdb_ewa=dict(psnr_rgb=psnr(ewa[..., :3], cyc[..., :3]), psnr_alpha=psnr(ewa[..., 3], cyc[..., 3]),
                     psnr_rgb_inner=psnr(ewa[..., :3][inner], cyc[..., :3][inner]),
                     rms_rgb=math.sqrt(mse_rgb), rms_rgb_beyond_noise=bias_rgb, mean_rgb=ewa_mean.tolist(),
                     mean_ratio_rgb=ratio, mean_ratio_stderr=ratio_err,
                     alpha_mean_ratio=float(ewa[..., 3][mask].mean() / cyc[..., 3][mask].mean())),
    )

    if check_renders:
        ga, gb = read_rgba(check_renders[0]["exr"]), read_rgba(check_renders[1]["exr"])
        gimg = 0.5 * (ga + gb)
        gstats = stats(ga, gb, gimg)
        g2 = args.check_anisotropy
        ratio_g = float(np.mean(gstats["mean_rgb"]) / np.mean(cstats["mean_rgb"]))
        check = dict(anisotropy=g2, cycles=gstats, mean_ratio_to_main=ratio_g,
                     mean_ratio_stderr=math.hypot(gstats["mean_stderr"] / np.mean(gstats["mean_rgb"]),
                                                  cstats["mean_stderr"] / np.mean(cstats["mean_rgb"])) * ratio_g)

        def hg(c, g):  # 4 pi p_HG: relative to isotropic
            return (1 - g * g) / (1 + g * g - 2 * g * c) ** 1.5

        if args.bounces == 0 and args.anisotropy == 0.0:
            # Single scattering from a sun: each ray's light is isotropic's times the phase at its one angle.
            for name, sign in (("forward_positive", 1.0), ("mirrored", -1.0)):
                factor = (hg(sign * cos_t, g2) / hg(sign * cos_t, 0.0))[..., None]
                predicted = cyc[..., :3] * factor
                predicted_ewa = ewa[..., :3] * factor
                check["prediction_" + name] = dict(
                    psnr_rgb_from_cycles=psnr(predicted, gimg[..., :3]), psnr_rgb_from_vdb_ewa=psnr(predicted_ewa, gimg[..., :3]),
                    noise_psnr_rgb=gstats["noise_psnr_rgb"],  # what the noise of Cycles' mean at G2 allows vdb_ewa's prediction
                    mean_ratio_predicted=float(predicted[mask].mean() / cyc[..., :3][mask].mean()),
                    factor_at_centre=float(hg(sign * (sun_dir @ forward), g2)))
        summary["check_anisotropy"] = check

    with open(out("summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    table = format_table(summary)
    with open(out("summary.txt"), "w") as f:
        f.write(table)
    print(table, end="")

    # PNGs: vdb_ewa | Cycles | difference x 4, sRGB over black.
    def srgb(x):
        x = np.clip(x, 0.0, 1.0)
        return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)

    diff = (ewa[..., :3] - cyc[..., :3]).mean(axis=-1) * 4.0
    diff_img = np.stack([np.clip(diff, 0, None), np.zeros_like(diff), np.clip(-diff, 0, None)], axis=-1)
    gap = np.full((height, 2, 3), 0.2)
    panels = [srgb(ewa[..., :3]), gap, srgb(cyc[..., :3]), gap, srgb(diff_img)]
    if check_renders:
        panels += [gap, srgb(gimg[..., :3])]
    write_png(oiio, out("compare.png"), np.concatenate(panels, axis=1))
    write_png(oiio, out("vdb_ewa.png"), srgb(ewa[..., :3]))
    write_png(oiio, out("cycles.png"), srgb(cyc[..., :3]))
    return 0


def option_name(token):
    """A CLI option's name without its dashes and value (--method=x, -method, -t: method, method, translate)."""
    name = token.lstrip("-").split("=", 1)[0]
    return {"t": "translate", "r": "rotate", "q": "quiet", "v": "verbose", "density-grid": "name"}.get(name, name)


def without_overridden(cli, extra):
    """@a cli without the options @a extra gives again (the CLI takes each option once): extra's win.
    Every option of @a cli past its input and output takes one value, but -q."""
    given = {option_name(t) for t in extra if t.startswith("-") and not t.lstrip("-")[:1].isdigit()}
    kept, i = cli[:3], 3
    while i < len(cli):
        token = cli[i]
        takes_value = token != "-q" and "=" not in token
        if option_name(token) not in given:
            kept += cli[i:i + 1 + takes_value]
        i += 1 + takes_value
    return kept


def write_png(oiio, path, rgb):
    import numpy as np
    data = (np.clip(rgb, 0, 1) * 255 + 0.5).astype(np.uint8)
    spec = oiio.ImageSpec(data.shape[1], data.shape[0], 3, oiio.UINT8)
    o = oiio.ImageOutput.create(path)
    o.open(path, spec)
    o.write_image(data)
    o.close()


def format_table(s):
    st, c, e = s["settings"], s["cycles"], s["vdb_ewa"]
    rgb = lambda v: "%.4f, %.4f, %.4f" % tuple(v)
    lines = [
        "fog sphere: radius 1 (%d voxels of %.5g), Density %g (optical depth %.3g across), albedo %g; sun %g towards %s;"
        % (st["radius_voxels"], st["voxel_size"], st["density"], st["optical_depth_across"], st["albedo"], st["sun_strength"],
           ", ".join("%.3f" % x for x in st["sun_dir_unit"])),
        "  eye %s; angle sun propagation to view %.1f deg (scattering angle at the centre %.1f deg); %s, %d pixels in the silhouette"
        % (st["eye"], st["angle_sun_propagation_to_view_deg"], st["scattering_angle_at_centre_deg"], st["res"], st["silhouette_pixels"]),
        "Cycles: Volume Bounces %d, Anisotropy %g, %d samples, seeds %d and %d, step rate %g; vdb_ewa extra args: %s"
        % (st["bounces"], st["anisotropy"], st["samples"], st["seed"], st["seed"] + 1, st["step_rate"], " ".join(st["vdb_ewa_args"]) or "none"),
        "",
        "| | PSNR RGB | PSNR alpha | PSNR RGB within 0.95 of the radius | mean RGB in silhouette | ratio to Cycles |",
        "|---|---|---|---|---|---|",
        "| Cycles seed vs seed | %.2f dB | %.2f dB | | | |" % (c["seed_psnr_rgb"], c["seed_psnr_alpha"]),
        "| Cycles' noise in its mean (rms %.2e RGB, %.2e alpha) | %.2f dB | %.2f dB | %.2f dB | %s (+- %.1e) | 1 |"
        % (c["noise_rms_rgb"], c["noise_rms_alpha"], c["noise_psnr_rgb"], c["noise_psnr_alpha"], c["noise_psnr_rgb_inner"],
           rgb(c["mean_rgb"]), c["mean_stderr"]),
        "| vdb_ewa vs Cycles' mean | %.2f dB | %.2f dB | %.2f dB | %s | %s (+- %.4f) |"
        % (e["psnr_rgb"], e["psnr_alpha"], e["psnr_rgb_inner"], rgb(e["mean_rgb"]), rgb(e["mean_ratio_rgb"]), e["mean_ratio_stderr"]),
        "",
        "vdb_ewa: RMS difference %.2e RGB, %.2e of it beyond Cycles' noise; alpha mean ratio %.4f; its shadow march "
        "(--shadowstep %g) expected %.2f %% too bright (with --method raymarch); %.1f s. Cycles: %s"
        % (e["rms_rgb"], e["rms_rgb_beyond_noise"], e["alpha_mean_ratio"], st["shadowstep"], 100 * st["shadow_march_brightening"],
           s["seconds"]["vdb_ewa"],
           ", ".join("%s %.0f s" % (k, v) for k, v in s["seconds"]["cycles_each"].items())),
    ]
    if "check_anisotropy" in s:
        k = s["check_anisotropy"]
        lines += ["",
                  "Cycles at Anisotropy %g: mean RGB %s in the silhouette: %.4f (+- %.4f) x Anisotropy %g's; seed vs seed %.2f dB"
                  % (k["anisotropy"], rgb(k["cycles"]["mean_rgb"]), k["mean_ratio_to_main"], k["mean_ratio_stderr"], st["anisotropy"],
                     k["cycles"]["seed_psnr_rgb"])]
        for name in ("forward_positive", "mirrored"):
            if "prediction_" + name in k:
                q = k["prediction_" + name]
                lines.append("  single scattering x 4 pi p_HG(%scos t) (%s): predicted ratio %.4f (%.3f at the centre); "
                             "PSNR against Cycles from Cycles' g=0 %.2f dB, from vdb_ewa %.2f dB (Cycles' noise allows %.2f dB)"
                             % ("" if name == "forward_positive" else "-", name.replace("_", " "), q["mean_ratio_predicted"],
                                q["factor_at_centre"], q["psnr_rgb_from_cycles"], q["psnr_rgb_from_vdb_ewa"], q["noise_psnr_rgb"]))
        if "prediction_forward_positive" in k:
            lines.append("  (the same seeds as Anisotropy %g's: at Volume Bounces 0 Cycles' samples differ only by the phase's weight, "
                         "so the prediction from Cycles' own image is exact where the convention is right)" % st["anisotropy"])
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    if "--blender-job" in sys.argv:
        blender_main(sys.argv[sys.argv.index("--blender-job") + 1])
    else:
        sys.exit(main())
