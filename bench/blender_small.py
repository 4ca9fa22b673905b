#!/usr/bin/python3
"""Issue 52's Blender figure: a dense cloud seen small, the vdb_ewa engine against Cycles.

One volume object of a .vdb file (default: the shared pyro) with a Principled Volume of Density
--density (4), a sun, a 50 mm camera far enough that a voxel spans --voxel-pixels pixels (0.5) at
--res (160x90), rendered by the vdb_ewa engine at each --quality and its method=raymarch (the
panel's Options), and by Cycles with --samples (single scattering: Volume Bounces 0, as
vdb_ewa's), in `blender -b`. Prints each render's brightness (sum of R, G, B) against Cycles',
PSNR over the object's footprint, and the render call's time.

    /usr/bin/python3 bench/blender_small.py [--module-dir build/python] [--samples 256]

Needs Blender (Debian's blender), numpy and OpenImageIO for /usr/bin/python3, the Python module
built (--module-dir) and the shared assets ($VDB_EWA_ASSETS)."""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import OpenImageIO as oiio

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ASSETS = os.environ.get("VDB_EWA_ASSETS", os.path.join(ROOT, "..", "shared", "grids"))

SCENE = r'''
import json, sys, time, bpy, mathutils
p = json.load(open(sys.argv[sys.argv.index("--") + 1]))
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
if p["engine"] == "VDB_EWA":
    sys.path.insert(0, p["addon_dir"])
    import vdb_ewa_render
    vdb_ewa_render.register()
    scene.vdb_ewa.quality = p["quality"]
    scene.vdb_ewa.extra_options = p["options"]
scene.render.engine = p["engine"]
scene.render.resolution_x, scene.render.resolution_y = p["res"]
scene.render.resolution_percentage = 100
scene.render.film_transparent = True
scene.view_settings.view_transform = "Standard"
if p["engine"] == "CYCLES":
    scene.cycles.samples = p["samples"]
    scene.cycles.use_denoising = False
    scene.cycles.volume_bounces = 0
    scene.cycles.device = "CPU"
volume = bpy.data.volumes.new("asset")
volume.filepath = p["asset"]
obj = bpy.data.objects.new("asset", volume)
scene.collection.objects.link(obj)
sys.path.insert(0, p["materials_dir"])
from blender_materials import principled_volume
volume.materials.append(principled_volume("cloud", p["grid"], p["density"], (0.5, 0.5, 0.5)))  # the node's default colour
camera_data = bpy.data.cameras.new("camera")
camera_data.lens, camera_data.sensor_width = 50.0, 36.0
camera_data.clip_start, camera_data.clip_end = 0.1, 1e5
camera = bpy.data.objects.new("camera", camera_data)
scene.collection.objects.link(camera)
eye, target = mathutils.Vector(p["eye"]), mathutils.Vector(p["target"])
camera.matrix_world = mathutils.Matrix.LocRotScale(eye, (target - eye).to_track_quat("-Z", "Y"), None)
scene.camera = camera
sun_data = bpy.data.lights.new("sun", "SUN")
sun_data.energy = 3.0
sun = bpy.data.objects.new("sun", sun_data)
scene.collection.objects.link(sun)
sun.matrix_world = mathutils.Matrix.LocRotScale(None, mathutils.Vector((1.0, 0.3, 0.6)).to_track_quat("Z", "Y"), None)
t0 = time.monotonic()
bpy.ops.render.render()
print("render-seconds %.3f" % (time.monotonic() - t0))
bpy.data.images["Render Result"].save_render(p["out"])
'''


def read_rgba(path):
    image = oiio.ImageInput.open(path)
    spec = image.spec()
    pixels = np.asarray(image.read_image(format="float")).reshape(spec.height, spec.width, spec.nchannels)
    image.close()
    return np.stack([pixels[..., list(spec.channelnames).index(c)] for c in "RGBA"], axis=-1)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--asset", default=os.path.join(ASSETS, "pyro.vdb"))
    ap.add_argument("--grid", default="density")
    ap.add_argument("--voxel-size", type=float, default=0.075, help="the asset's voxel size, world units")
    ap.add_argument("--target", default="0.225,2.175,-0.225", help="the point looked at (the asset's centre)")
    ap.add_argument("--voxel-pixels", type=float, default=0.5)
    ap.add_argument("--res", default="160x90")
    ap.add_argument("--density", type=float, default=4.0)
    ap.add_argument("--samples", type=int, default=256)
    ap.add_argument("--quality", default="draft,default,high,final")
    ap.add_argument("--module-dir", default=os.path.join(ROOT, "build", "python"))
    args = ap.parse_args()
    w, h = (int(x) for x in args.res.split("x"))
    target = [float(x) for x in args.target.split(",")]
    distance = args.voxel_size * (w * 50.0 / 36.0) / args.voxel_pixels
    eye = [target[0], target[1], target[2] + distance]
    tmp = tempfile.mkdtemp(prefix="vdb_ewa_blender_small_")
    script = os.path.join(tmp, "scene.py")
    with open(script, "w") as f:
        f.write(SCENE)
    env = dict(os.environ, PYTHONPATH=os.path.abspath(args.module_dir))

    def render(name, **params):
        p = dict(asset=os.path.abspath(args.asset), grid=args.grid, res=[w, h], density=args.density, eye=eye, target=target,
                 addon_dir=os.path.join(ROOT, "plugins", "blender"), materials_dir=os.path.join(ROOT, "tests", "blender"), out=os.path.join(tmp, name + ".exr"), **params)
        with open(os.path.join(tmp, name + ".json"), "w") as f:
            json.dump(p, f)
        r = subprocess.run(["blender", "-b", "--factory-startup", "--python", script, "--", os.path.join(tmp, name + ".json")],
                           capture_output=True, text=True, env=env)
        seconds = [float(l.split()[-1]) for l in r.stdout.splitlines() if l.startswith("render-seconds")]
        if r.returncode != 0 or not seconds:
            sys.exit(f"blender failed for {name}:\n{r.stdout[-2000:]}\n{r.stderr[-2000:]}")
        return read_rgba(p["out"]), seconds[0]

    cycles, t_cycles = render("cycles", engine="CYCLES", samples=args.samples)
    ys, xs = np.nonzero(cycles[..., 3] > 1e-3)
    sl = np.s_[max(ys.min() - 2, 0):ys.max() + 3, max(xs.min() - 2, 0):xs.max() + 3]
    print(f"# {os.path.basename(args.asset)}, Density {args.density}, {args.res}, a voxel {args.voxel_pixels} pixels "
          f"(camera {distance:.4g} units away); Cycles {args.samples} samples, Volume Bounces 0: {t_cycles:.1f} s")
    print("| render | brightness against Cycles | PSNR (footprint) | time (s) |")
    print("|---|---|---|---|")
    runs = [(f"vdb_ewa {q}", dict(quality=q, options="")) for q in args.quality.split(",")]
    runs += [("vdb_ewa default, supersample=1", dict(quality="default", options="supersample=1")),
             ("vdb_ewa method=raymarch", dict(quality="default", options="method=raymarch, pixel_samples=16"))]
    for name, params in runs:
        image, seconds = render(name.replace(" ", "_").replace(",", "").replace("=", ""), engine="VDB_EWA", **params)
        a, b = image[sl], cycles[sl]
        mse = float(((a[..., :3] - b[..., :3]) ** 2).mean())
        psnr = 10 * np.log10(1.0 / mse) if mse > 0 else float("inf")
        print(f"| {name} | {100 * (a[..., :3].sum() / b[..., :3].sum() - 1):+.1f} % | {psnr:.1f} dB | {seconds:.2f} |", flush=True)


if __name__ == "__main__":
    main()
