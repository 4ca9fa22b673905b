#!/usr/bin/python3
"""docs/blender_render.png and docs/blender_vs_cycles.png (docs/blender.md): the Blender test
scene of commit dc78dbf (one volume object of the shared pyro, moved, scaled unevenly and
rotated, with a Principled Volume; a 35 mm camera; a sun) at 640x360, rendered in `blender -b`:

- blender_render.png: Blender's own render result through the vdb_ewa engine (default quality),
  saved as a PNG (Standard view) and laid over the grey background;
- blender_vs_cycles.png: 2x2 panels over the same grey, each labelled with the time of the
  render call alone (bpy.ops.render.render) and its PSNR (R, G, B, A of the saved float EXRs)
  against the Cycles reference: the vdb_ewa engine, Cycles at 16 samples, Cycles at
  --reference-samples (1024), EEVEE.

The scene is the test's as it was when the figures were made: tests/blender/run_blender_test.py
and blender_scene.py of commit dc78dbf, read with `git show` (the test's scene has since gained
a second volume, a spot light, a lens and motion blur), with the add-on of this checkout
(plugins/blender). Cycles' 1024 samples take about two minutes on two cores; everything else
about 40 s. EEVEE needs an OpenGL context: headless it runs where Mesa's surfaceless EGL
platform is available (EGL_PLATFORM=surfaceless is set for it); where it cannot start, its
panel says so.

Needs Blender (Debian's blender), git, vdb_ewa ($VDB_EWA_BIN, default vdb_ewa on PATH), the
Python module built beside it (--module-dir, default BIN/../../python: the build tree's
layout), numpy, pyopenvdb and OpenImageIO for /usr/bin/python3, oiiotool, the DejaVu Sans font
and the shared assets ($VDB_EWA_ASSETS, default ../shared/grids).

Usage: docs/figures/make_blender.py [--out DIR] [--module-dir DIR] [--reference-samples N]
  writes DIR/blender_render.png and DIR/blender_vs_cycles.png (default DIR: a new temporary
  folder; --out docs replaces the committed images)."""
import argparse
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np
import OpenImageIO as oiio

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENE_COMMIT = "dc78dbf"
GREY = "0.2196,0.2392,0.2784,1"   # the background, sRGB-encoded (56, 61, 71)
FONT = os.environ.get("FIGURE_FONT", "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf")


def read_rgba(path):
    image = oiio.ImageBuf(path)
    if image.has_error:
        sys.exit(f"cannot read {path}: {image.geterror()}")
    spec = image.spec()
    pixels = image.get_pixels(oiio.FLOAT)
    names = list(spec.channelnames)
    return np.stack([pixels[..., names.index(c)] for c in "RGBA"], axis=-1)


def psnr(a, b):
    mse = float(np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2))
    return math.inf if mse == 0.0 else 10.0 * math.log10(1.0 / mse)


def seconds_text(t):
    return f"{t:.2f}" if t < 1 else f"{t:.1f}" if t < 100 else f"{t:.0f}"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="", help="the folder for the two PNGs (default: a new temporary folder)")
    parser.add_argument("--module-dir", default="", help="the folder of the built Python module vdb_ewa")
    parser.add_argument("--reference-samples", type=int, default=1024, help="Cycles' samples for the reference")
    args = parser.parse_args()
    ewa = os.environ.get("VDB_EWA_BIN", os.environ.get("VDB_EWA", "vdb_ewa"))
    ewa = os.path.abspath(ewa) if os.sep in ewa else (shutil.which(ewa) or ewa)
    for tool in (ewa, "blender", "git", "oiiotool"):
        if shutil.which(tool) is None:
            sys.exit(f"{sys.argv[0]}: {tool} not found (set VDB_EWA_BIN for vdb_ewa)")
    if not os.path.isfile(FONT):
        sys.exit(f"{sys.argv[0]}: font {FONT} not found (fonts-dejavu-core, or set FIGURE_FONT)")
    module_dir = os.path.abspath(args.module_dir or os.path.join(os.path.dirname(ewa), "..", "..", "python"))
    if not os.path.isdir(module_dir) or not any(f.startswith("vdb_ewa") and f.endswith(".so") for f in os.listdir(module_dir)):
        sys.exit(f"{sys.argv[0]}: no Python module vdb_ewa in {module_dir} (give --module-dir)")
    assets = os.path.abspath(os.environ.get("VDB_EWA_ASSETS", os.path.join(ROOT, "..", "shared", "grids")))
    if not os.path.isfile(os.path.join(assets, "pyro.vdb")):
        sys.exit(f"{sys.argv[0]}: {assets}/pyro.vdb not found (set VDB_EWA_ASSETS)")
    out = os.path.abspath(args.out or tempfile.mkdtemp(prefix="vdb_ewa_figure_"))
    os.makedirs(out, exist_ok=True)

    with tempfile.TemporaryDirectory() as tmp:
        scene_dir = os.path.join(tmp, "scene")
        os.makedirs(scene_dir)
        for name in ("run_blender_test.py", "blender_scene.py"):
            text = subprocess.run(["git", "-C", ROOT, "show", f"{SCENE_COMMIT}:tests/blender/{name}"], check=True,
                                  capture_output=True, text=True).stdout
            with open(os.path.join(scene_dir, name), "w") as f:
                f.write(text)

        def render(name, engine, extra=(), env=None):
            """Blender's saved result (EXR, PNG) and the render call's seconds, or None."""
            folder = os.path.join(tmp, name)
            done = subprocess.run([sys.executable, os.path.join(scene_dir, "run_blender_test.py"), "--cli", ewa,
                                   "--module-dir", module_dir, "--addon-dir", os.path.join(ROOT, "plugins", "blender"),
                                   "--out", folder, "--res", "640x360", "--engine", engine, *extra],
                                  capture_output=True, text=True, env=dict(os.environ, VDB_EWA_ASSETS=assets, **(env or {})))
            log = os.path.join(folder, "blender.log")
            timing = re.findall(r"blender_scene: \S+ rendered in ([0-9.]+) s", open(log).read()) if os.path.isfile(log) else []
            if not timing or not os.path.isfile(os.path.join(folder, "blender.png")):
                print(f"{name}: Blender gave no image:\n{(done.stdout + done.stderr)[-1500:]}", file=sys.stderr)
                return None
            print(f"{name}: {float(timing[0]):.2f} s", flush=True)
            return os.path.join(folder, "blender.exr"), os.path.join(folder, "blender.png"), float(timing[0])

        engine = render("vdb_ewa", "VDB_EWA")
        cycles16 = render("cycles16", "CYCLES", ["--samples", "16"])
        reference = render("reference", "CYCLES", ["--samples", str(args.reference_samples)])
        eevee = render("eevee", "BLENDER_EEVEE", env={"EGL_PLATFORM": "surfaceless"})
        if engine is None or reference is None:
            sys.exit("the vdb_ewa engine's or Cycles' reference render failed (above)")
        truth = read_rgba(reference[0])
        decibels = lambda r: psnr(read_rgba(r[0]), truth)

        def panel(result, title, note, path):
            command = ["oiiotool", "--create", "640x360", "4", "--fill:color=" + GREY, "640x360"]
            if result:
                command = ["oiiotool", result[1], "--ch", "R,G,B,A", *command[1:], "--over"]
            command += ["--text:x=12:y=30:size=20:color=1,1,1:font=" + FONT, title]
            if note:
                command += ["--text:x=12:y=346:size=16:color=0.851,0.851,0.851:font=" + FONT, note]
            subprocess.run([*command, "-d", "uint8", "-o", path], check=True)

        # Blender's render result over the grey, unlabelled.
        subprocess.run(["oiiotool", engine[1], "--ch", "R,G,B,A", "--create", "640x360", "4",
                        "--fill:color=" + GREY, "640x360", "--over", "-d", "uint8", "-o",
                        os.path.join(out, "blender_render.png")], check=True)
        panels = [os.path.join(tmp, f"panel{i}.png") for i in range(4)]
        spp = args.reference_samples
        panel(engine, "vdb_ewa engine (default)",
              f"{seconds_text(engine[2])} s, {decibels(engine):.1f} dB against Cycles {spp} spp", panels[0])
        panel(cycles16, "Cycles, 16 samples",
              f"{seconds_text(cycles16[2])} s, {decibels(cycles16):.1f} dB" if cycles16 else "(Cycles failed)", panels[1])
        panel(reference, f"Cycles, {spp} samples (reference)", f"{seconds_text(reference[2])} s (adaptive sampling)", panels[2])
        panel(eevee, "EEVEE (headless, software GL)",
              f"{seconds_text(eevee[2])} s, {decibels(eevee):.1f} dB (no volume self-shadowing by default)" if eevee
              else "(EEVEE could not start here: no OpenGL context)", panels[3])
        subprocess.run(["oiiotool", *panels, "--mosaic", "2x2", "-d", "uint8", "-o",
                        os.path.join(out, "blender_vs_cycles.png")], check=True)
    print(os.path.join(out, "blender_render.png"))
    print(os.path.join(out, "blender_vs_cycles.png"))


if __name__ == "__main__":
    main()
