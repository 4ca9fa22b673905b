#!/usr/bin/python3
"""docs/checker_grazing.png (docs/equations.md, the paper's Fig. 15): a checker texture at a
grazing angle, 320x240 each, 4 pixels apart. Left: volume kernels on a fog sheet two voxels
thick, scaled to the surface panel's mean (the scale is printed; the caption's x2.84 was the
renderer's at commit 14d7c5a); middle: EWA surface splats on a level-set plane; right: the same
plane with point-sampled footprints (--aa none). Linear values through the sRGB curve.

The scenes are those of tests/surface_test.cpp (CheckerPlane): the plane y = 0 as a level set
(voxel 0.05, narrow band 3 voxels, i in [-160, 160], k in [-400, 40]) or as a fog sheet of
density 3 in the voxel rows j = -1 and 0, with a vec3s colour grid `checker` of squares of two
voxels; the camera 0.5 units above the plane looks at (0, 0, -6). The surfaces use the matte
shader; the sheet is lit from above (--light 0,1,0,1,1,1 --absorb 0 --scatter 1 --shadowstep
0.25). Written here with pyopenvdb; a few seconds in all.

Needs vdb_ewa ($VDB_EWA_BIN, default vdb_ewa on PATH), numpy, pyopenvdb and OpenImageIO for
/usr/bin/python3, and oiiotool. No shared asset.

Usage: docs/figures/make_checker_grazing.py [--out DIR]
  writes DIR/checker_grazing.png (default DIR: a new temporary folder; --out docs replaces the
  committed image)."""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np
import OpenImageIO as oiio
import pyopenvdb as vdb

H = 0.05                          # voxel size
I_HALF, K_LO, K_HI = 160, -400, 40
CAMERA = ["--res", "320x240", "--translate", "0,0.5,2", "--lookat", "0,0,-6"]


def transform():
    return vdb.createLinearTransform(voxelSize=H)


def checker():
    """The colour grid: ((i >> 1) + (k >> 1)) & 1 in grey, active over j in [-3, 3]."""
    i = np.arange(-I_HALF, I_HALF + 1)[:, None, None]
    k = np.arange(K_LO, K_HI + 1)[None, None, :]
    value = (((i >> 1) + (k >> 1)) & 1).astype(np.float32)
    value = np.broadcast_to(value, (2 * I_HALF + 1, 7, K_HI - K_LO + 1))
    grid = vdb.Vec3SGrid()
    grid.transform = transform()
    grid.name = "checker"
    # A negative tolerance keeps every voxel active, the black squares too (as the test's grid).
    grid.copyFromArray(np.repeat(value[..., None], 3, axis=3).copy(), ijk=(-I_HALF, -3, K_LO), tolerance=(-1.0, -1.0, -1.0))
    return grid


def plane():
    """The level set of y = 0: active where |y| < 3 voxels (rows j = -2..2), inactive values
    -band below (rows -3, -4) and +band (the background) above, as tests/fixtures.h makeLevelSet."""
    band = 3.0 * H
    grid = vdb.FloatGrid(band)
    grid.transform = transform()
    grid.name = "surface"
    grid.gridClass = vdb.GridClass.LEVEL_SET
    rows = (np.arange(-2, 3) * H).astype(np.float32)
    grid.copyFromArray(np.broadcast_to(rows[None, :, None], (2 * I_HALF + 1, 5, K_HI - K_LO + 1)).copy(),
                       ijk=(-I_HALF, -2, K_LO), tolerance=-1.0)
    accessor = grid.getAccessor()
    for j in (-3, -4):
        for i in range(-I_HALF, I_HALF + 1):
            for k in range(K_LO, K_HI + 1):
                accessor.setValueOff((i, j, k), -band)
    return grid


def sheet():
    """The fog sheet: density 3 (optical depth 3 per voxel length) in rows j = -1 and 0."""
    grid = vdb.FloatGrid(0.0)
    grid.transform = transform()
    grid.name = "density"
    grid.gridClass = vdb.GridClass.FOG_VOLUME
    grid.copyFromArray(np.full((2 * I_HALF + 1, 2, K_HI - K_LO + 1), 3.0, np.float32), ijk=(-I_HALF, -1, K_LO))
    return grid


def rgb(path):
    image = oiio.ImageBuf(path)
    if image.has_error:
        sys.exit(f"cannot read {path}: {image.geterror()}")
    return image.get_pixels(oiio.FLOAT)[..., :3]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="", help="the folder for checker_grazing.png (default: a new temporary folder)")
    args = parser.parse_args()
    ewa = os.environ.get("VDB_EWA_BIN", os.environ.get("VDB_EWA", "vdb_ewa"))
    for tool in (ewa, "oiiotool"):
        if shutil.which(tool) is None:
            sys.exit(f"{sys.argv[0]}: {tool} not found (set VDB_EWA_BIN)")
    out = os.path.abspath(args.out or tempfile.mkdtemp(prefix="vdb_ewa_figure_"))
    os.makedirs(out, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        path = lambda name: os.path.join(tmp, name)
        vdb.write(path("plane.vdb"), grids=[plane(), checker()])
        vdb.write(path("sheet.vdb"), grids=[sheet(), checker()])
        render = lambda *a: subprocess.run([ewa, *a, *CAMERA, "--color", "checker", "-q"], check=True)
        render(path("sheet.vdb"), path("volume.exr"), "--light", "0,1,0,1,1,1", "--absorb", "0", "--scatter", "1", "--shadowstep", "0.25")
        render(path("plane.vdb"), path("ewa.exr"), "--shader", "matte")
        render(path("plane.vdb"), path("none.exr"), "--shader", "matte", "--aa", "none")
        # The volume panel scaled to the surface panel's mean over the rows nearest the camera.
        scale = float(rgb(path("ewa.exr"))[120:].mean() / rgb(path("volume.exr"))[120:].mean())
        panels = []
        for name, gain in (("volume", scale), ("ewa", 1.0), ("none", 1.0)):
            subprocess.run(["oiiotool", path(name + ".exr"), "--ch", "R,G,B", "--mulc", f"{gain:.6f}",
                            "--colorconvert", "linear", "sRGB", "-o", path(name + ".png")], check=True)
            panels.append(path(name + ".png"))
        target = os.path.join(out, "checker_grazing.png")
        subprocess.run(["oiiotool", *panels, "--mosaic:pad=4", "3x1", "-d", "uint8", "-o", target], check=True)
    print(f"{target}: volume kernels scaled x{scale:.2f} to the surface splats' mean")


if __name__ == "__main__":
    main()
