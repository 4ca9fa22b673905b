"""The add-on's Rendered viewport in Blender with a window (Xvfb): tests/blender/viewport_scene.py
switches a 3D view of the shared pyro to Rendered shading, orbits it, looks through the camera and
F12-renders that view; this driver checks what it recorded and screenshot:

- every view change drew a new vdb_ewa image: a refined image after each, its screenshot of the 3D
  view not empty (against the view's background) and unlike the previous view's;
- the add-on's camera keywords for each view give Blender's own projection (window_matrix) and
  view matrix (perspective, orthographic, through the camera);
- the camera view's screenshot is F12's image of the same view: F12's EXR composited over the
  view's background and encoded as the Standard view transform does, against the screenshot, by
  silhouette (IoU of the pixels off the background) and mean colour;
- the console lines are the engine's records, in the documented form;
- a bad option is shown (printed once, no traceback), and the view renders again once it is gone;

and prints the times: first image after the switch, per view change the coarse and refined image
(docs/blender.md#the-rendered-viewport). Exit 77 (ctest's skip) where Blender, xvfb-run, numpy,
OpenImageIO or the asset (pyro.vdb) is missing.

    python3 run_viewport_test.py --module-dir build/python --addon-dir plugins/blender --out OUTDIR \\
        [--default-assets ../shared/grids] [--runs 3] (figures: medians over the runs)
"""
import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import time

from driver_support import read_image as read, skip


# Thresholds, from measured values (docs/blender.md#the-rendered-viewport has them).
MIN_COVERAGE = 0.02  # of the view's pixels off its background (measured 0.14 to 0.25; 0 when view_draw draws nothing)
MIN_VIEW_CHANGE = 0.005  # mean |difference| of two views' screenshots, 0-1 (measured 0.016 to 0.035 for 25° orbits)
MIN_IOU = 0.95  # camera view against F12 (measured 0.985-0.993; 0.68 with the view's camera turned 3°, 0.90 zoomed 3 %)
MAX_MEAN_COLOUR = 0.01  # |mean colour difference| per channel, 0-1 (measured 0.0005)
MIN_PSNR = 45.0  # camera view against F12, display-encoded RGB (measured 57.1 dB)
OFF_BACKGROUND = 8.0 / 255.0  # a pixel is off the background where a channel differs by more
LINE = re.compile(r"^vdb_ewa viewport: (\d+)x(\d+) (draft/\d+|draft|default|high|final) in (\d+\.\d+) s "
                  r"\(reused: (\d+) light maps, (\d+) light rays\)$")


try:
    import numpy as np
    import OpenImageIO as oiio
except ImportError as e:
    skip("needs numpy and OpenImageIO for Python (python3-openimageio): %s" % e)


def srgb_encode(linear):
    linear = np.clip(linear, 0.0, 1.0)
    return np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * np.power(linear, 1.0 / 2.4) - 0.055)


def srgb_decode(encoded):
    return np.where(encoded <= 0.04045, encoded / 12.92, np.power((encoded + 0.055) / 1.055, 2.4))


MARGIN = 12  # pixels of the view's border left out: the area's rounded corners and its hidden regions' arrows


def view_of(shot, window, region):
    """The 3D view's pixels (RGB, 0-1, rows top to bottom) of a window screenshot, but MARGIN."""
    pixels, _ = read(shot)
    x, y, width, height = region
    top = window[1] - (y + height)
    return pixels[top + MARGIN:top + height - MARGIN, x + MARGIN:x + width - MARGIN, :3]


def run_blender(args, out, asset):
    params = dict(addon_dir=os.path.abspath(args.addon_dir), asset=os.path.abspath(asset), grid="density", out=out,
                  quality=args.quality, region=[args.width, args.height], orbits=args.orbits, orbit_degrees=25.0,
                  density=args.density, color=[0.8, 0.8, 0.8], sun_strength=4.0, sun_direction=[0.4, -0.3, 0.8],
                  focal=35.0, eye_direction=[0.3, -0.9, 0.4], view_lens=50.0, view_distance=1.0, wait_seconds=30.0,
                  settle_seconds=15.0, shading=args.shading)
    with open(os.path.join(out, "params.json"), "w") as f:
        json.dump(params, f, indent=1)
    env = dict(os.environ, VDB_EWA_PYTHONPATH=os.path.abspath(args.module_dir))
    command = ["xvfb-run", "-a", "-s", "-screen 0 1280x800x24", "blender", "--factory-startup", "--python-exit-code", "1",
               "--python", os.path.join(os.path.dirname(os.path.abspath(__file__)), "viewport_scene.py"), "--",
               os.path.join(out, "params.json")]
    t0 = time.monotonic()
    done = subprocess.run(command, capture_output=True, text=True, env=env, timeout=300)
    log = done.stdout + done.stderr
    with open(os.path.join(out, "blender.log"), "w") as f:
        f.write(log)
    result_path = os.path.join(out, "viewport.json")
    if not os.path.isfile(result_path):
        sys.exit("FAIL: blender exited %d without a result; its log ends:\n%s" % (done.returncode, log[-3000:]))
    with open(result_path) as f:
        result = json.load(f)
    if result["failure"]:
        sys.exit("FAIL: %s; the log ends:\n%s" % (result["failure"], log[-3000:]))
    print("blender: %.1f s in all (run in %s)" % (time.monotonic() - t0, out))
    return result, log


def check_run(result, log):
    """The checks above on one run; returns its times."""
    records, window, region = result["records"], result["window"], result["region"]
    if region[2:] != [r for r in (records[-1]["width"], records[-1]["height"])]:
        sys.exit("FAIL: the engine's images are %dx%d, the 3D view %dx%d" % (records[-1]["width"], records[-1]["height"], *region[2:]))
    # The console: one line per image drawn, as the records say.
    lines = [line for line in log.splitlines() if line.startswith("vdb_ewa viewport:")]
    if lines != [r["line"] for r in records]:
        sys.exit("FAIL: the console's lines are not the engine's records:\n%s\n%s" % ("\n".join(lines), [r["line"] for r in records]))
    for line in lines:
        if not LINE.match(line):
            sys.exit("FAIL: a console line not of the documented form: %r" % line)
    # The one error: the bad option the script set last, printed once, no traceback; then a new image.
    errors = [line for line in log.splitlines() if line.startswith("vdb_ewa: ") or "Traceback" in line]
    if len(errors) != 1 or "bogus" not in errors[0]:
        sys.exit("FAIL: expected the bad option's error once, got:\n" + "\n".join(errors))
    if records[-1]["requested"] < result["changes"][-1]["t"]:
        sys.exit("FAIL: no image after the bad option was taken back")

    # The add-on's camera keywords against Blender's projection and view matrices, each view.
    for change in result["changes"]:
        if "projection" not in change:  # the recovery after the bad option
            continue
        ours, blender = change["projection"]
        print("%s view: 2 focal / aperture (or 2 / frame) %.5f, Blender's projection %.5f; rotation off by %.1e, eye by %.1e"
              % (change["what"], ours, blender, change["rotation"], change["eye"]))
        if abs(ours / blender - 1.0) > 1e-4 or change["rotation"] > 1e-4 or change["eye"] > 1e-4:
            sys.exit("FAIL: the %s view's camera keywords are not Blender's view" % change["what"])

    # Each view: not empty, unlike the one before.
    views = [view_of(shot, window, region) for shot in result["shots"]]
    background = np.median(np.concatenate([views[0][:4].reshape(-1, 3), views[0][-4:].reshape(-1, 3)]), axis=0)
    previous = None
    for index, view in enumerate(views):
        coverage = float((np.abs(view - background).max(axis=-1) > OFF_BACKGROUND).mean())
        change = None if previous is None else float(np.abs(view - previous).mean())
        print("view %d: %.3f of the pixels off the background%s" % (index, coverage, "" if change is None else ", %.4f mean change" % change))
        if coverage < MIN_COVERAGE:
            sys.exit("FAIL: view %d (%s) shows no volume: %.3f of its pixels off the background %s" % (index, result["shots"][index], coverage, background))
        if change is not None and change < MIN_VIEW_CHANGE:
            sys.exit("FAIL: view %d (%s) is the view before it: mean change %.4f" % (index, result["shots"][index], change))
        previous = view

    # The camera view against F12 of the same view, both over the background, display-encoded.
    pixels, names = read(result["f12"])
    f12 = np.stack([pixels[..., names.index(c)] for c in "RGBA"], axis=-1)[MARGIN:-MARGIN, MARGIN:-MARGIN]
    if f12.shape[:2] != views[-1].shape[:2]:
        sys.exit("FAIL: F12's image is %s, the view %s" % (f12.shape, views[-1].shape))
    composited = srgb_encode(f12[..., :3] + srgb_decode(background) * (1.0 - f12[..., 3:4]))
    camera_view = views[-1]
    mask_f12 = np.abs(composited - background).max(axis=-1) > OFF_BACKGROUND
    mask_view = np.abs(camera_view - background).max(axis=-1) > OFF_BACKGROUND
    iou = float((mask_f12 & mask_view).sum() / max(1, (mask_f12 | mask_view).sum()))
    colour = np.abs(composited.reshape(-1, 3).mean(axis=0) - camera_view.reshape(-1, 3).mean(axis=0))
    psnr = 10.0 * np.log10(1.0 / max(1e-12, float(np.mean((composited - camera_view) ** 2))))
    print("camera view against F12: silhouette IoU %.4f (F12 %.3f, view %.3f of the pixels), mean colour differs by %s, "
          "%.1f dB PSNR; F12's alpha > 0.05 on %.3f" % (iou, mask_f12.mean(), mask_view.mean(), np.array2string(colour, precision=4),
                                                      psnr, float((f12[..., 3] > 0.05).mean())))
    if iou < MIN_IOU:
        sys.exit("FAIL: the camera view's silhouette is not F12's: IoU %.4f < %.2f" % (iou, MIN_IOU))
    if colour.max() > MAX_MEAN_COLOUR:
        sys.exit("FAIL: the camera view's mean colour is not F12's: %s > %.3f" % (colour, MAX_MEAN_COLOUR))
    if psnr < MIN_PSNR:
        sys.exit("FAIL: the camera view is not F12's image: %.1f dB < %.0f dB" % (psnr, MIN_PSNR))
    # Where an orbit's time goes: the view change to the render's request (view_draw), the render
    # (to the image handed over), the image to its drawing (the timer, the redraw).
    orbits = [c["t"] for c in result["changes"] if c["what"] == "orbit"]
    stages = {True: [], False: []}
    for t in orbits:
        for coarse in (True, False):
            r = next((r for r in records if r["requested"] >= t and r["coarse"] == coarse), None)
            if r is not None:
                stages[coarse].append((r["requested"] - t, r["ready"] - r["requested"], r["drawn"] - r["ready"]))
    return dict(stages=stages, first_coarse=result["switch"]["coarse"], first_refined=result["switch"]["refined"],
                coarse=[c["coarse"] for c in result["changes"] if c["what"] == "orbit"],
                refined=[c["refined"] for c in result["changes"] if c["what"] == "orbit"],
                camera_refined=[c["refined"] for c in result["changes"] if c["what"] == "camera"][0],
                f12=result["f12_seconds"])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--module-dir", required=True)
    parser.add_argument("--addon-dir", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--default-assets", default="", help="the assets' folder where $VDB_EWA_ASSETS is not set")
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--height", type=int, default=360)
    parser.add_argument("--orbits", type=int, default=4)
    parser.add_argument("--runs", type=int, default=1, help="Blender runs (figures: medians over them)")
    parser.add_argument("--quality", default="default")
    parser.add_argument("--density", type=float, default=4.0)
    parser.add_argument("--shading", default="RENDERED", help="RENDERED (the test) or MATERIAL (Material Preview draws the same)")
    args = parser.parse_args()

    for tool in ("blender", "xvfb-run"):
        if shutil.which(tool) is None:
            skip("%s is not installed (scripts/install-deps.sh --test installs blender and xvfb)" % tool)
    assets = os.environ.get("VDB_EWA_ASSETS", args.default_assets)
    asset = os.path.join(assets, "pyro.vdb") if assets else ""
    if not os.path.isfile(asset):
        skip("the asset pyro.vdb is not found (--default-assets or $VDB_EWA_ASSETS: %r)" % assets)

    times = []
    for run in range(args.runs):
        out = os.path.abspath(os.path.join(args.out, "run%d" % run))
        shutil.rmtree(out, ignore_errors=True)
        os.makedirs(out)
        times.append(check_run(*run_blender(args, out, asset)))
        t = times[-1]
        fmt = lambda xs: ", ".join("-" if x is None else "%.3f" % x for x in xs)
        print("run %d: first image %s s coarse, %.3f s refined; orbits: coarse %s s, refined %s s; camera view %.3f s; F12 %.3f s"
              % (run, "-" if t["first_coarse"] is None else "%.3f" % t["first_coarse"], t["first_refined"], fmt(t["coarse"]),
                 fmt(t["refined"]), t["camera_refined"], t["f12"]))
    median = lambda xs: statistics.median(xs) if xs else float("nan")
    coarse = [x for t in times for x in t["coarse"] if x is not None]
    print("medians over %d run(s), %s, %dx%d: first image %.3f s coarse, %.3f s refined; a view change %.3f s coarse (%d of %d "
          "changes drew one), %.3f s refined" % (
              args.runs, args.quality, args.width, args.height, median([t["first_coarse"] for t in times if t["first_coarse"] is not None]),
              median([t["first_refined"] for t in times]), median(coarse), len(coarse), sum(len(t["coarse"]) for t in times),
              median([x for t in times for x in t["refined"]])))
    for coarse, name in ((True, "coarse"), (False, "refined")):
        rows = [x for t in times for x in t["stages"][coarse]]
        if rows:
            print("an orbit's %s image, medians: %.3f s to the request, %.3f s rendering, %.3f s to the screen"
                  % (name, *(median([row[i] for row in rows]) for i in range(3))))
    print("PASS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
