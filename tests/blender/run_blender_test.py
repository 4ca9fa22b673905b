"""The Blender add-on in the real client: blender -b builds a scene (a volume object loading a
.vdb file, moved by a rotation, a non-uniform scale and a translation, with a Principled Volume,
and motion-blurred by a velocity grid in its file; a camera aimed at a point, with depth of field;
a sun and a spot light; a second volume object with a material of its own, still, interpenetrating
the first), renders it through the vdb_ewa engine in-process, and saves
Blender's render result. The CLI renders the same scene from options this script derives on its
own (the grid rewritten with the moved transform by pyopenvdb, --lookat for the camera, the
material and lights by docs/blender.md's formulas); the two must agree to 60 dB PSNR.

Exit 77 (ctest's skip) with a message where Blender, pyopenvdb or OpenImageIO is missing.

    python3 run_blender_test.py --cli build/cmd/vdb_ewa/vdb_ewa --module-dir build/python \
        --addon-dir plugins/blender --out OUTDIR [--engine CYCLES --samples 64]  (figures)
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import time

from driver_support import read_image, skip



try:
    import numpy as np
    import OpenImageIO as oiio
    import pyopenvdb
except ImportError as e:
    skip("needs numpy, OpenImageIO and pyopenvdb for Python (python3-openimageio, python3-openvdb): %s" % e)


# The octaves a scene with Volume Bounces gets (scene_mapping.SCATTERING_OCTAVES, measured:
# docs/lighting.md#multiple-scattering).
EXPECTED_OCTAVES = 4


def read_rgba(path):
    pixels, names = read_image(path)
    return np.stack([pixels[..., names.index(c)] for c in "RGBA"], axis=-1)


def psnr(a, b):
    mse = float(np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2))
    return math.inf if mse == 0.0 else 10.0 * math.log10(1.0 / mse)


def matrix_of(transform):
    """A linear pyopenvdb transform as a 4x4 column-vector matrix (from its images of the axes)."""
    o = np.array(transform.indexToWorld((0, 0, 0)))
    m = np.eye(4)
    for axis in range(3):
        e = [0, 0, 0]
        e[axis] = 1
        m[:3, axis] = np.array(transform.indexToWorld(tuple(e))) - o
    m[:3, 3] = o
    return m


def rotation_z(degrees):
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cli", required=True)
    parser.add_argument("--module-dir", required=True)
    parser.add_argument("--addon-dir", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--default-assets", default="", help="the assets' folder where $VDB_EWA_ASSETS is not set")
    parser.add_argument("--res", default="320x180")
    parser.add_argument("--engine", default="VDB_EWA", help="VDB_EWA (the test) or CYCLES (a figure)")
    parser.add_argument("--samples", type=int, default=64, help="Cycles samples (--engine CYCLES)")
    parser.add_argument("--seed", type=int, default=0, help="Cycles' seed (--engine CYCLES)")
    parser.add_argument("--quality", default="default")
    args = parser.parse_args()

    blender = shutil.which("blender")
    if blender is None:
        skip("Blender is not installed (Debian's blender; scripts/install-deps.sh --test installs it)")
    os.makedirs(args.out, exist_ok=True)
    out = lambda name: os.path.join(args.out, name)

    # The asset: the shared pyro when present, else the sample cloud.
    assets = os.environ.get("VDB_EWA_ASSETS", args.default_assets)
    asset = os.path.join(assets, "pyro.vdb") if assets else ""
    if not os.path.isfile(asset):
        asset = out("cloud.vdb")
        subprocess.run([args.cli, "make-grid", "cloud", asset], check=True, capture_output=True)
    grid = pyopenvdb.readAll(asset)[0][0]
    file_map = matrix_of(grid.transform)
    centre = file_map @ np.array([*(np.add(*grid.evalActiveVoxelBoundingBox()) / 2.0), 1.0])

    # The object's transform: scaled unevenly in its own axes, rotated, moved (loc/rot/scale hold no shear).
    object_to_world = rotation_z(20) @ np.diag([1.5, 1.0, 0.8, 1.0])
    object_to_world[:3, 3] = (1.0, -0.5, 0.3)
    # A second object of the same asset, unscaled (finer voxels: the base of the engine's sum),
    # shifted to interpenetrate the first.
    second_to_world = rotation_z(-35) @ np.eye(4)
    second_to_world[:3, 3] = (1.0, -0.5, 0.3)
    second_to_world[:3, 3] += (object_to_world @ centre)[:3] - (second_to_world @ centre)[:3] + file_map[:3, :3] @ np.array([15.0, 0.0, 5.0])
    target = (object_to_world @ centre)[:3]
    extent = np.linalg.norm(file_map[:3, :3] @ (np.array(grid.evalActiveVoxelBoundingBox()[1]) - grid.evalActiveVoxelBoundingBox()[0]))
    eye = target + extent * np.array([0.25, -0.9, 0.35])
    # The first object moves: the asset with a uniform velocity grid, world units per second of its
    # object space (x Blender's Velocity Scale): about 6 voxels along its x and 2 along its z over
    # the shutter (half a frame at 24 fps).
    voxel_size = grid.transform.voxelSize()[0]
    velocity_file = np.array([192.0, 0.0, 64.0]) * voxel_size
    velocity_grid = pyopenvdb.Vec3SGrid()
    velocity_grid.name = "velocity"
    velocity_grid.transform = grid.transform
    lo, hi = grid.evalActiveVoxelBoundingBox()
    velocity_grid.fill(lo, hi, tuple(velocity_file), True)
    pyopenvdb.write(out("moving.vdb"), grids=[pyopenvdb.readAll(asset)[0][0], velocity_grid])
    width, height = map(int, args.res.split("x"))
    params = dict(engine=args.engine, addon_dir=os.path.abspath(args.addon_dir), asset=os.path.abspath(asset), grid=grid.name,
                  moving_asset=out("moving.vdb"), velocity_scale=1.5, shutter=0.5, fps=24,
                  res=[width, height], object_to_world=object_to_world.tolist(), second_object_to_world=second_to_world.tolist(), density=2.0, color=[0.9, 0.7, 0.5],
                  absorption_color=[0.3, 0.2, 0.6], second_density=1.5, second_color=[0.5, 0.7, 0.9],
                  second_absorption_color=[0.7, 0.6, 0.3], focal=35.0, sensor=36.0, clip=[0.01, 1000.0], eye=eye.tolist(),
                  target=target.tolist(), sun_strength=4.0, sun_color=[1.0, 0.9, 0.8],
                  sun_direction=(np.array([0.4, -0.3, 0.8]) / np.linalg.norm([0.4, -0.3, 0.8])).tolist(),
                  fstop=0.1, focus_distance=0.8 * float(np.linalg.norm(target - eye)),
                  spot_position=(target + extent * np.array([-0.6, -0.5, 0.5])).tolist(), spot_power=40.0 * extent * extent,
                  spot_color=[0.6, 0.8, 1.0], spot_angle=40.0, spot_blend=0.3, spot_radius=0.01 * extent,
                  cycles_samples=args.samples, cycles_seed=args.seed,
                  # The vdb_ewa engine's: Principled Volume's Anisotropy and Cycles' Volume Bounces.
                  anisotropy=0.4 if args.engine == "VDB_EWA" else 0.0, volume_bounces=3 if args.engine == "VDB_EWA" else 0, quality=args.quality, exr=out("blender.exr"), png=out("blender.png"))
    with open(out("params.json"), "w") as f:
        json.dump(params, f, indent=1)
    env = dict(os.environ, VDB_EWA_PYTHONPATH=os.path.abspath(args.module_dir))
    t0 = time.monotonic()
    done = subprocess.run([blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python",
                           os.path.join(os.path.dirname(os.path.abspath(__file__)), "blender_scene.py"), "--", out("params.json")],
                          capture_output=True, text=True, env=env, timeout=1800)
    blender_seconds = time.monotonic() - t0
    log = done.stdout + done.stderr
    with open(out("blender.log"), "w") as f:
        f.write(log)
    if done.returncode != 0 or not os.path.isfile(out("blender.exr")):
        sys.exit("FAIL: blender exited %d; its log ends:\n%s" % (done.returncode, log[-3000:]))
    errors = [line for line in log.splitlines() if "vdb_ewa:" in line and "Error" in line]
    if errors:
        sys.exit("FAIL: the engine reported:\n" + "\n".join(errors))
    print("blender: %.2f s from start to saved result (%s)" % (blender_seconds, args.engine))
    print([line for line in log.splitlines() if line.startswith("blender_scene:")][-1])
    if args.engine != "VDB_EWA":
        return 0

    # The CLI's image of the same scene, from this script's own derivation.
    moved = pyopenvdb.readAll(asset)[0][0]
    half_voxel = np.eye(4)
    half_voxel[:3, 3] = 0.5  # Blender's voxel (i, j, k) is at the centre of the index cell [i, i + 1]^3
    composite = object_to_world @ file_map @ half_voxel
    moved.transform = pyopenvdb.createLinearTransform(composite.T.tolist())  # OpenVDB: row vectors
    # Its velocities in the world: turned and scaled by the object's transform, as Blender moves them.
    moved_velocity = pyopenvdb.Vec3SGrid()
    moved_velocity.name = "velocity"
    moved_velocity.transform = moved.transform
    moved_velocity.fill(lo, hi, tuple(object_to_world[:3, :3] @ velocity_file), True)
    pyopenvdb.write(out("moved.vdb"), grids=[moved, moved_velocity])
    # The second object: finer voxels (unscaled), so the sum's base, rendered first.
    second = pyopenvdb.readAll(asset)[0][0]
    second_composite = second_to_world @ file_map @ half_voxel
    second.transform = pyopenvdb.createLinearTransform(second_composite.T.tolist())
    pyopenvdb.write(out("second.vdb"), grids=[second])
    def coefficients(prefix, voxel):
        """docs/blender.md's Principled Volume formulas, per voxel length: (scatter, absorb)."""
        color, absorption, density = np.array(params[prefix + "color"]), np.array(params[prefix + "absorption_color"]), params[prefix + "density"]
        return color * density * voxel, np.maximum(1 - color, 0) * np.maximum(1 - np.sqrt(absorption), 0) * density * voxel

    # Each object its own material: the second's is the input's, the first's the added volume's.
    scatter, absorb = coefficients("second_", abs(np.linalg.det(second_composite[:3, :3])) ** (1.0 / 3.0))
    moved_scatter, moved_absorb = coefficients("", abs(np.linalg.det(composite[:3, :3])) ** (1.0 / 3.0))
    light = list(params["sun_direction"]) + list(np.array(params["sun_color"]) * params["sun_strength"] / (4 * math.pi))
    join = lambda v: ",".join("%.17g" % x for x in v)
    # The spot: Cycles' intensity power / 4 pi, scattered isotropically (1 / 4 pi), aimed at the target.
    spot = (list(params["spot_position"]) + list(target) + [params["spot_angle"], params["spot_blend"]]
            + list(np.array(params["spot_color"]) * params["spot_power"] / (16 * math.pi * math.pi)))
    cli = [args.cli, out("second.vdb"), out("cli.exr"), "--name", grid.name, "--add-volume", out("moved.vdb") + ":" + grid.name,
           "--add-volume-material", "absorb=%s scatter=%s" % (join(moved_absorb), join(moved_scatter)), "--res", args.res, "--translate", join(eye),
           "--lookat", join(target), "--up", "0,0,1", "--focal", "35", "--aperture", "36", "--near", "0.01", "--far", "1000",
           "--fstop", "%.17g" % params["fstop"], "--focus-distance", "%.17g" % params["focus_distance"],
           "--velocity-grid", "velocity", "--velocity-unit", "second", "--velocity-scale", "%.17g" % params["velocity_scale"],
           "--fps", "%.17g" % params["fps"], "--shutter", "%.17g,%.17g" % (-0.5 * params["shutter"], 0.5 * params["shutter"]),
           "--light", join(light), "--spot-light", join(spot), "--point-light-radius", "%.17g" % params["spot_radius"], "--gain", "0", "--scatter", join(scatter), "--absorb", join(absorb), "--quality", args.quality,
           "--working-space", "lin_rec709", "--output-space", "lin_rec709", "--exr-type", "float", "-q",
           # Anisotropy is --anisotropy; 3 Volume Bounces are --multiple-scattering min(1 + 3, the add-on's SCATTERING_OCTAVES).
           "--anisotropy", "%.17g" % params["anisotropy"], "--multiple-scattering", str(min(1 + params["volume_bounces"], EXPECTED_OCTAVES))]
    done = subprocess.run(cli, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit("FAIL: the CLI exited %d: %s" % (done.returncode, done.stderr))
    engine, reference = read_rgba(out("blender.exr")), read_rgba(out("cli.exr"))
    if engine.shape != reference.shape:
        sys.exit("FAIL: Blender's image is %s, the CLI's %s" % (engine.shape, reference.shape))
    value = psnr(engine, reference)
    coverage = float((reference[..., 3] > 0.05).mean())
    print("engine against the CLI: %.1f dB PSNR (RGBA); alpha max %.3f (CLI %.3f), %.0f %% of pixels covered"
          % (value, engine[..., 3].max(), reference[..., 3].max(), 100 * coverage))
    if coverage < 0.05:
        sys.exit("FAIL: the CLI's image is nearly empty: the test scene does not frame the grid")
    if value < 60.0:  # they agree to 120 dB or more; a Velocity Scale of 1 for 1.5 gives 41 dB
        sys.exit("FAIL: %.1f dB < 60 dB: the engine's scene conversion differs from the CLI's" % value)
    # Esc: the engine stopped after its second progress report, well before a final render's end.
    with open(out("blender.exr") + ".progress.json") as f:
        progress = json.load(f)
    reports = progress["cancelled_reports"]
    print("Esc: progress %s, cancelled after %.2f s (a default render: %.2f s)"
          % (", ".join("%.2f" % r for r in reports), progress["cancelled_seconds"], progress["full_seconds"]))
    if len(reports) < 2 or reports != sorted(reports) or not 0.0 <= reports[0] < 1.0:
        sys.exit("FAIL: the engine's progress reports do not rise from 0 to 1: %s" % reports)
    if reports[-1] >= 1.0 or len(reports) > 3:
        sys.exit("FAIL: the render was not cancelled when test_break() turned true: %s" % reports)
    print("PASS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
