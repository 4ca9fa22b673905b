#!/usr/bin/python3
"""vdb_ewa benchmarks: run outside the unit tests, ratios against vdb_render in the same run.

  bench/bench.py speed  [--res 1920x1080] [--repeat 3]   time per asset, vdb_ewa / vdb_render
  bench/bench.py sigma  [--res 480x270]                  --kernel-sigma sweep: error vs converged vdb_render
  bench/bench.py tradeoff [--scenes smoke,pyro] [--res 960x540] [--plot docs/pareto.png] [--cache DIR]
                                                         presets and knob sweeps: time and error against
                                                         (a) --method raymarch at a fine step and
                                                         (b) vdb_render's converged image
  bench/bench.py plot TABLE.txt --plot OUT.png           redraw the Pareto plot from a saved tradeoff table
  bench/bench.py analytic [--res 320x180]                 issue 14's analytic field: a sum of Gaussian blobs
                                                         sampled onto a grid; the truth integrates the
                                                         blobs themselves (closed-form shadows); the
                                                         presets and vdb_render's settings against it
  bench/bench.py ladder [--scenes all] [--res 960x540] [--cache DIR] [--plot OUT.png]
                                                         issue 14's ladder: draft, default, high and
                                                         vdb_render's settings on every scene, time and
                                                         PSNR against vdb_render's converged image
  bench/bench.py targets --cache DIR [--scene smoke] [--res 1920x1080] [--repeat 5]
                                                         issue 3's targets: vdb_render's defaults and
                                                         the presets in interleaved rounds (PSNR too
                                                         where DIR holds a tradeoff run's references)
  bench/bench.py surfaces [--res 1920x1080] [--shader diffuse] [--repeat 3]
                                                         level sets: surface splats against vdb_render
  bench/bench.py imagelod-scale [--res 480x270] [--px 0.1,3,20]
                                                         issue 54: --image-lod's levels at both ends of
                                                         scale, thin and thick, against off
  bench/bench.py draft [--res 1920x1080] [--repeat 3]   issue 54: --quality draft against default and
                                                         vdb_render's defaults, interleaved
  bench/bench.py roofline [--res 1920x1080] [--quality draft,default] [--build DIR]
                                                         issue 17: the rasteriser's achieved rate against
                                                         the peak of its inner loop (bench/roofline)
  bench/bench.py tiles                                   issue 52, in time: files of active tiles seen from
                                                         afar (time, memory) and a cube of tiles against
                                                         the reference
  bench/bench.py scaling [--res 1920x1080] [--millions 0.1,0.3,1,3,10,30,100] [--peer-max 3]
                                                         issue 17: time and peak memory against active
                                                         voxels, on the sample cloud made finer
                                                         (make-grid), vdb_render up to --peer-max M
  bench/bench.py stability [--res 480x270] [--frames 24] [--quality default,draft] [--scenes all]
                                                         issue 17: frame-to-frame change along an orbit
                                                         and a dolly of each scene, default against draft
  bench/bench.py holes [--res 640x480] [--only sphere,cube] [--keep DIR]
                                                         issue 16's coverage: IoU and holes against
                                                         vdb_render's hit mask (-shader matte), level
                                                         sets from far, default, ortho, close-up and
                                                         grazing cameras, and the time of both
  bench/bench.py python [--scene smoke] [--res 960x540] [--repeat 7]
                                                         issue 19: the Python module against the CLI on the
                                                         same settings (import to array, and with the EXR
                                                         written), vdb_render in the same rounds
  bench/bench.py scene | turntable | progressive | soak [--scenes pyro,smoke] [--res 960x540] [--quality default] [--repeat N]
                                                         issue 55: a Scene's camera move against a cold
                                                         render; a 24-frame turntable against 24
                                                         processes (--frames); a progressive render's
                                                         coarse and asked images, cold and warm (480x270);
                                                         resident memory over 100 camera moves (--moves)
  bench/bench.py cull [--res 1920x1080] [--repeat 3]      issue 37's streamed frame: --cull on against off
                                                         and vdb_render's defaults, README and default
                                                         cameras, with the streamed frame's counters
  bench/bench.py blur [--res 480x270] [--repeat 3] [--ref-samples 64] [--keep DIR]
                                                         issue 38: motion blur (generated velocities) and
                                                         depth of field on pyro and the cloud, default and
                                                         high against the reference integrator's shutter
                                                         and lens samples, time against the still frame
  bench/bench.py lights [--res 480x270] [--repeat 3] [--keep DIR]
                                                         point and spot lights (inside the volume and
                                                         from outside) on pyro and the cloud, default and
                                                         high against the reference's shadow rays, time
                                                         against the frame with its directional light only
  bench/bench.py volumes [--res 480x270] [--repeat 3] [--keep DIR]
                                                         --add-volume: pyro with the cloud inside it, one
                                                         sweep against the reference of the volumes in
                                                         one field and against compositing them over
                                                         each other; the cloud with the input's medium
                                                         and with its own (--add-volume-material)
  bench/bench.py scale [--res 240x135] [--px 0.1,0.3,1,3] [--scenes all] [--repeat 3]
                                                         issue 52: the presets where voxels span a tenth
                                                         of a pixel to 3 pixels, thin and thick, against
                                                         the reference integrator supersampled; time
                                                         against vdb_render's defaults in the same run
  bench/bench.py output [--scene smoke] [--res 1920x1080] [--repeat 3]
                                                         issue 4's output stage: EXR pixel types,
                                                         compressions, passes and deep files, with
                                                         vdb_render's defaults in the same rounds

Needs a Release build in build/ (scripts/setup.sh; $VDB_EWA_BIN names another vdb_ewa), vdb_render and the shared assets
($VDB_EWA_ASSETS, default ../shared/grids); the Pareto plot needs python3-matplotlib, the
analytic field and `holes` python3-numpy, python3-openvdb and python3-openimageio (Debian's:
scripts/install-deps.sh --bench; run with /usr/bin/python3).
Machines are noisy: compare ratios, not seconds.
"""
import argparse
import json
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

nan = float("nan")

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EWA = os.environ.get("VDB_EWA_BIN", os.path.join(ROOT, "build", "cmd", "vdb_ewa", "vdb_ewa"))
# The speed and accuracy verbs write float EXRs, vdb_render's file type, so that both pay the
# same for the file and PSNR is not capped by half precision; `output` measures the file types.
EWA_RENDER = [EWA, "render", "--exr-type", "float"]
ASSETS = os.environ.get("VDB_EWA_ASSETS", os.path.join(ROOT, "..", "shared", "grids"))

# (label, file, camera args in vdb_render syntax, which vdb_render can read)
SCENES = [
    ("smoke", f"{ASSETS}/smoke.vdb", "-translate -7.381,40.48,237.4 -lookat -7.381,40.48,0.4762"),
    ("pyro", f"{ASSETS}/pyro.vdb", "-translate 0.225,2.175,15.75 -lookat 0.225,2.175,-0.225"),
    ("pig", f"{ASSETS}/pig.vdb", "-translate 0,0,2.49 -lookat 0,0,0"),
    ("fog_tommy_v5", f"{ASSETS}/fog_tommy_v5.vdb", "-translate 0,0.875,3.65 -lookat 0,0.875,0"),
    ("brain_mri", f"{ASSETS}/brain_mri.vdb", "-translate 62.5,70.5,281 -lookat 62.5,70.5,41.5"),
    ("cloud (grids/)", f"{ROOT}/grids/cloud.vdb", "-translate 1.5,0.8,4.5 -lookat 0,0,0"),
    ("tiles (grids/)", f"{ROOT}/grids/tiles.vdb", "-translate 1.5,0.8,4.5 -lookat 0,0,0"),
]
# Grids vdb_render cannot read (double values, non-uniform voxels): timed against vdb_render on
# a uniform float resampling of the same field, written by `vdb_ewa make-grid`.
PROXIES = [
    ("smoke_double (double)", f"{ASSETS}/smoke_double.vdb", "-translate 63.5,31.5,318 -lookat 63.5,31.5,31.5", None),
    ("anisotropic (grids/)", f"{ROOT}/grids/anisotropic.vdb", "-translate 1.5,0.8,4.5 -lookat 0,0,0", ("cloud", 0.08)),
    ("sheared (grids/)", f"{ROOT}/grids/sheared.vdb", "-translate 1.5,0.8,4.5 -lookat 0,0,0", ("cloud", 0.04)),
]


def run(cmd):
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    dt = time.perf_counter() - t0
    if p.returncode != 0:
        sys.exit(f"failed: {' '.join(cmd)}\n{p.stderr}")
    return dt, p.stdout


def stages(stdout):
    m = re.search(r"timings \(s\): (.*)", stdout)
    return dict((k, float(v)) for k, v in re.findall(r"(\w+) ([0-9.]+)", m.group(1))) if m else {}




def diff(a, b, channels="R,G,B"):
    """(RMS error, PSNR in dB) of two EXRs over @channels, computed by oiiotool --diff."""
    out = subprocess.run(["oiiotool", a, "--ch", channels, b, "--ch", channels, "--diff"],
                         capture_output=True, text=True).stdout
    m = re.search(r"RMS error = ([0-9.e+-]+)", out)
    if m is None and "PASS" in out:
        return 0.0, float("inf")  # identical: oiiotool prints no error figures
    rms = float(m.group(1))
    snr = re.search(r"Peak SNR = ([0-9.e+-]+|inf)", out)
    return rms, (float(snr.group(1)) if snr else float("inf"))


def cmd_speed(args):
    tmp = tempfile.mkdtemp(prefix="vdb_ewa_bench_")
    res = ["-res", args.res]
    print(f"# vdb_ewa vs vdb_render, {args.res}, median of {args.repeat} interleaved runs, {os.cpu_count()} cores")
    print("| scene | voxels | vdb_render (s) | vdb_ewa (s) | speed-up | load | kernels | shadows | project | rasterise | write |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    scenes = [(l, f, c, None) for (l, f, c) in SCENES] + PROXIES
    for label, path, cam, proxy in scenes:
        if not os.path.exists(path):
            print(f"| {label} | missing | | | | | | | | | |")
            continue
        ref_path = path
        if proxy is not None:
            ref_path = os.path.join(tmp, "proxy.vdb")
            run([EWA, "make-grid", proxy[0], ref_path, "--voxel-size", str(proxy[1])])
        elif label.startswith("smoke_double"):
            ref_path = None  # no float twin on disk: vdb_render column is left empty
        ours, theirs, st = [], [], []
        for _ in range(args.repeat):
            dt, out = run([*EWA_RENDER, path, os.path.join(tmp, "ours.exr"), *res, *cam.split(), "-v"])
            ours.append(dt)
            st.append(stages(out))
            if ref_path:
                dt, _ = run(["vdb_render", ref_path, os.path.join(tmp, "theirs.exr"), *res, *cam.split()])
                theirs.append(dt)
        o = statistics.median(ours)
        t = statistics.median(theirs) if theirs else float("nan")
        s = {k: statistics.median(x[k] for x in st) for k in st[0]}
        vox = re.search(r"(\d+) active voxels", run([*EWA_RENDER, path, os.path.join(tmp, "o.exr"), "-res", "8x8", *cam.split(), "-v"])[1]).group(1)
        ratio = f"{t / o:.1f}x" if theirs else "n/a"
        tt = f"{t:.2f}" if theirs else "n/a (double grid)"
        print(f"| {label} | {vox} | {tt} | {o:.2f} | {ratio} | {s['load']:.3f} | {s['kernels']:.3f} | "
              f"{s['shadows']:.3f} | {s['project']:.3f} | {s['rasterise']:.3f} | {s['write']:.3f} |", flush=True)


def cmd_sigma(args):
    tmp = tempfile.mkdtemp(prefix="vdb_ewa_sigma_")
    res = ["-res", args.res]
    sigmas = [0.45, 0.5, 0.55, 0.6, 0.7, 0.8, 1.0]
    print(f"# --kernel-sigma sweep at {args.res}: PSNR (dB, RGB) against vdb_render's converged image "
          "(-step 0.125 -shadowstep 0.375); vdb_ewa with the same --shadowstep 0.375, so the columns differ "
          "only in the reconstruction kernel; vdb_render's defaults for comparison")
    print("| scene | vdb_render defaults | " + " | ".join(f"sigma {s}" for s in sigmas) + " |")
    print("|---|---|" + "---|" * len(sigmas))
    for label, path, cam in SCENES:
        if not os.path.exists(path):
            continue
        conv = os.path.join(tmp, "conv.exr")
        run(["vdb_render", path, conv, *res, *cam.split(), "-step", "0.125", "-shadowstep", "0.375"])
        run(["vdb_render", path, os.path.join(tmp, "def.exr"), *res, *cam.split()])
        row = [f"{diff(os.path.join(tmp, 'def.exr'), conv)[1]:.1f}"]
        for s in sigmas:
            run([*EWA_RENDER, path, os.path.join(tmp, "ours.exr"), *res, *cam.split(), "--kernel-sigma", str(s),
                 "--shadowstep", "0.375"])
            row.append(f"{diff(os.path.join(tmp, 'ours.exr'), conv)[1]:.1f}")
        print(f"| {label} | " + " | ".join(row) + " |", flush=True)


# Knob sweeps around --quality default, and the presets (label, extra vdb_ewa arguments).
EWA_CONFIGS = [
    ("quality draft", ["--quality", "draft"]),
    ("quality default", ["--quality", "default"]),
    ("quality high", ["--quality", "high"]),
    ("quality final", ["--quality", "final"]),
    ("quality draft --lod 0", ["--quality", "draft", "--lod", "0"]),
] + [(f"--cutoff-radius {v}", ["--cutoff-radius", v]) for v in ["2", "2.5", "4"]] \
  + [(f"--slab {v}", ["--slab", v]) for v in ["0.5", "2", "4"]] \
  + [(f"--lowpass {v}", ["--lowpass", v]) for v in ["0.3", "2"]] \
  + [(f"--kernel-sigma {v}", ["--kernel-sigma", v]) for v in ["0.45", "0.7"]] \
  + [(f"--shadowstep {v}", ["--shadowstep", v]) for v in ["0.375", "1", "6"]] \
  + [(f"--exp {v}", ["--exp", v]) for v in ["exact", "table"]] \
  + [(f"--lod {v}", ["--lod", v]) for v in ["0", "6", "12"]] \
  + [("--renormalize off", ["--renormalize", "off"]), ("--aa swan", ["--aa", "swan"]), ("--aa none", ["--aa", "none"])]
# vdb_render's curve: its defaults and finer steps (label, arguments).
VDB_CONFIGS = [
    ("vdb_render defaults", []),
    ("vdb_render -step 0.5 -shadowstep 1.5", ["-step", "0.5", "-shadowstep", "1.5"]),
    ("vdb_render -step 0.25 -shadowstep 0.75", ["-step", "0.25", "-shadowstep", "0.75"]),
]


def timed(cmd, repeat):
    times = []
    for _ in range(repeat):
        times.append(run(cmd)[0])
    return statistics.median(times)


def reference_paths(cache, label, res):
    """Where a tradeoff run keeps (vdb_render's converged image, the raymarch reference)."""
    key = f"{label.split()[0]}_{res}"
    return os.path.join(cache, f"{key}_conv.exr"), os.path.join(cache, f"{key}_ref.exr")


def cmd_tradeoff(args):
    tmp = tempfile.mkdtemp(prefix="vdb_ewa_tradeoff_")
    wanted = args.scenes.split(",")
    # smoke_double: vdb_render cannot read double grids, so only the raymarch yardstick applies.
    scenes = [(l, f, c, True) for (l, f, c) in SCENES] + [(l, f, c, False) for (l, f, c, _) in PROXIES[:1]]
    scenes = [s for s in scenes if s[0].split()[0] in wanted]
    rows = []
    for label, path, cam, peer in scenes:
        if not os.path.exists(path):
            continue
        for res in args.res.split(","):
            common = ["-res", res, *cam.split()]
            # The two reference images are not timed: --cache keeps them between runs (vdb_render's
            # converged image takes about 10 minutes at 1920x1080 on 2 cores).
            cache = args.cache or tmp
            os.makedirs(cache, exist_ok=True)
            conv, ref = reference_paths(cache, label, res)
            if peer and not os.path.exists(conv):
                run(["vdb_render", path, conv, *common, "-step", "0.125", "-shadowstep", "0.375"])
            if not os.path.exists(ref):
                run([*EWA_RENDER, path, ref, *common, "--method", "raymarch", "--step", "0.25",
                     "--shadowstep", "0.375", "--shadow-res", "1", "--kernel-sigma", "0.55"])
            print(f"# {label} {res}: references {conv if peer else '(no vdb_render)'}, {ref}", flush=True)
            configs = [("vdb_render", l, ["vdb_render", path, os.path.join(tmp, "o.exr"), *common, *a])
                       for l, a in VDB_CONFIGS] if peer else []
            configs += [("vdb_ewa", l, [*EWA_RENDER, path, os.path.join(tmp, "o.exr"), *common, *a])
                        for l, a in EWA_CONFIGS]
            for renderer, name, cmd in configs:
                t = timed(cmd, args.repeat)
                out = os.path.join(tmp, "o.exr")
                rms_a, psnr_a = diff(out, ref)
                alpha_a = diff(out, ref, "A")[0]
                rms_b, psnr_b, alpha_b = (*diff(out, conv), diff(out, conv, "A")[0]) if peer else (nan, nan, nan)
                rows.append(dict(scene=label, res=res, renderer=renderer, config=name, time=t, psnr_ref=psnr_a,
                                 rmse_ref=rms_a, alpha_ref=alpha_a, psnr_conv=psnr_b, rmse_conv=rms_b,
                                 alpha_conv=alpha_b))
                print(f"| {label} | {res} | {name} | {t:.2f} | {psnr_a:.1f} | {rms_a:.4f} | {alpha_a:.4f} | "
                      f"{psnr_b:.1f} | {rms_b:.4f} | {alpha_b:.4f} |", flush=True)
    if args.plot:
        plot([r for r in rows if r["psnr_conv"] == r["psnr_conv"]], args.plot)


def cmd_plot(args):
    """Redraw the Pareto plot from the table a tradeoff run printed (saved to a file)."""
    rows = []
    for line in open(args.table):
        c = [x.strip() for x in line.strip().strip("|").split("|")]
        if not line.startswith("| ") or len(c) not in (6, 10) or c[0] == "scene":
            continue
        if len(c) == 10:  # a tradeoff table
            rows.append(dict(scene=c[0], res=c[1], config=c[2], time=float(c[3]), psnr_conv=float(c[7]),
                             renderer="vdb_render" if c[2].startswith("vdb_render") else "vdb_ewa"))
        else:  # a ladder table: scene, setting, time, ratio, PSNR, alpha RMSE
            rows.append(dict(scene=c[0], res=args.res, config=c[1], time=float(c[2]), psnr_conv=float(c[4]),
                             renderer="vdb_render" if c[1].startswith("vdb_render") else "vdb_ewa"))
    plot([r for r in rows if r["psnr_conv"] == r["psnr_conv"]], args.plot)


LADDER_EWA = [("quality draft", ["--quality", "draft"]), ("quality default", ["--quality", "default"]),
              ("quality high", ["--quality", "high"]), ("quality final", ["--quality", "final"]),
              ("quality final --shadow-res 0.25", ["--quality", "final", "--shadow-res", "0.25"])]
LADDER_VDB = VDB_CONFIGS + [("vdb_render -step 0.18 -shadowstep 0.5", ["-step", "0.18", "-shadowstep", "0.5"])]


def cmd_ladder(args):
    """Issue 14's figures: each preset and each vdb_render setting on every scene vdb_render can
    read, timed in the same run (median of --repeat), PSNR (RGB) against vdb_render's converged
    image (-step 0.125 -shadowstep 0.375, cached in --cache: it takes minutes)."""
    tmp = tempfile.mkdtemp(prefix="vdb_ewa_ladder_")
    wanted = None if args.scenes == "all" else args.scenes.split(",")
    cache = args.cache or tmp
    os.makedirs(cache, exist_ok=True)
    print(f"# {args.res}: median of {args.repeat} runs a setting, {os.cpu_count()} cores; PSNR (dB) against vdb_render converged")
    print("| scene | setting | time (s) | time / vdb_render defaults | PSNR (dB) | alpha RMSE |")
    print("|---|---|---|---|---|---|")
    rows = []
    for label, path, cam in SCENES:
        if (wanted and label.split()[0] not in wanted) or not os.path.exists(path):
            continue
        common = ["-res", args.res, *cam.split()]
        conv, _ = reference_paths(cache, label, args.res)
        if not os.path.exists(conv):
            run(["vdb_render", path, conv, *common, "-step", "0.125", "-shadowstep", "0.375"])
        out = os.path.join(tmp, "o.exr")
        configs = [("vdb_render", l, ["vdb_render", path, out, *common, *a]) for l, a in LADDER_VDB]
        configs += [("vdb_ewa", l, [*EWA_RENDER, path, out, *common, *a]) for l, a in LADDER_EWA]
        base = None
        for renderer, name, cmd in configs:
            t = timed(cmd, args.repeat)
            base = base or t
            psnr, alpha = diff(out, conv)[1], diff(out, conv, "A")[0]
            rows.append(dict(scene=label, res=args.res, renderer=renderer, config=name, time=t, psnr_conv=psnr))
            print(f"| {label} | {name} | {t:.2f} | {t / base:.2f} | {psnr:.1f} | {alpha:.4f} |", flush=True)
    if args.plot:
        plot(rows, args.plot)


# The analytic field: isotropic Gaussian blobs (centre x, y, z, std. deviation, peak density),
# index = world (voxel size 1), 64^3 voxels.
BLOBS = [(32, 30, 32, 9.0, 0.35), (22, 40, 28, 5.0, 0.6), (42, 24, 38, 6.0, 0.5), (36, 44, 22, 4.0, 0.8),
         (20, 20, 40, 3.0, 1.2), (46, 38, 44, 3.5, 0.9), (30, 22, 20, 2.5, 1.5), (40, 32, 30, 2.0, 2.0)]


def cmd_analytic(args):
    """A smooth procedural density sampled onto a grid. The truth integrates the blobs
    themselves: fine midpoint steps along each orthographic ray, the light's optical depth in
    closed form (erfc). Gain and cutoff are 0 in every renderer, so all integrate the same
    model; PSNR (RGB) of every setting against the truth, vdb_render's converged image first."""
    import math
    import numpy as np
    import pyopenvdb as vdb
    tmp = tempfile.mkdtemp(prefix="vdb_ewa_analytic_")
    w, h = (int(x) for x in args.res.split("x"))
    sigma_t, albedo, light_colour = 1.6, 1.5 / 1.6, 0.7
    light = np.array([0.3, 0.3, 0.0]) / math.hypot(0.3, 0.3)
    blobs = np.array(BLOBS, dtype=np.float64)

    def density(p):  # p: (..., 3) world = index positions
        d = np.zeros(p.shape[:-1])
        for cx, cy, cz, s, a in blobs:
            r2 = ((p - (cx, cy, cz)) ** 2).sum(-1)
            d += a * np.exp(-0.5 * r2 / (s * s))
        return d

    def erfc(x):  # Abramowitz and Stegun 7.1.26 (1.5e-7 absolute), vectorised
        a = np.abs(x)
        t = 1.0 / (1.0 + 0.3275911 * a)
        poly = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))))
        e = poly * np.exp(-a * a)
        return np.where(x >= 0, e, 2.0 - e)

    def light_depth(p):  # int_0^inf density(p + s light) ds, closed form per blob
        out = np.zeros(p.shape[:-1])
        for cx, cy, cz, s, a in blobs:
            v = np.array([cx, cy, cz]) - p
            t0 = v @ light
            perp2 = (v ** 2).sum(-1) - t0 ** 2
            out += a * np.exp(-0.5 * perp2 / (s * s)) * s * math.sqrt(math.pi / 2) * erfc(-t0 / (s * math.sqrt(2)))
        return out

    # The grid: values at voxel centres, active where > 1e-3.
    n = 64
    idx = np.stack(np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij"), -1).astype(np.float64)
    values = density(idx).astype(np.float32)
    values[values < 1e-3] = 0.0
    grid = vdb.FloatGrid()
    grid.copyFromArray(values, ijk=(0, 0, 0), tolerance=0.0)
    grid.name = "density"
    grid.gridClass = vdb.GridClass.FOG_VOLUME
    path = os.path.join(tmp, "blobs.vdb")
    vdb.write(path, grids=[grid])

    # The truth, orthographic camera down -z over [0, 64] x [14, 50] at z = 100 (vdb_render's
    # pixel centres at +0.5, rows downwards).
    frame, cx, cy = 64.0, 31.5, 31.5
    fh = frame * h / w
    xs = cx - frame / 2 + (np.arange(w) + 0.5) * frame / w
    ys = cy + fh / 2 - (np.arange(h) + 0.5) * fh / h
    X, Y = np.meshgrid(xs, ys)
    step = 0.05
    colour = np.zeros((h, w))
    depth = np.zeros((h, w))
    for z in np.arange(n + 2.0, -2.0, -step) - 0.5 * step:
        p = np.stack([X, Y, np.full_like(X, z)], -1)
        d = density(p)
        live = d > 1e-6
        if not live.any():
            continue
        tl = np.exp(-sigma_t * light_depth(p[live]))
        tau = sigma_t * d[live] * step
        colour[live] += np.exp(-depth[live]) * (-np.expm1(-tau)) * albedo * light_colour * tl
        depth[live] += tau
    # PFM (bottom row first) -> float EXR with oiiotool.
    pfm = os.path.join(tmp, "truth.pfm")
    rgb = np.repeat(colour[::-1, :, None], 3, axis=2).astype("<f4")
    with open(pfm, "wb") as f:
        f.write(f"PF\n{w} {h}\n-1.0\n".encode())
        f.write(rgb.tobytes())
    truth = os.path.join(tmp, "truth.exr")
    run(["oiiotool", pfm, "-d", "float", "-o", truth])

    common = ["-res", args.res, "-camera", "ortho", "-frame", str(frame), "-translate", f"{cx},{cy},100",
              "-gain", "0", "-cutoff", "0"]
    out = os.path.join(tmp, "o.exr")
    configs = [("vdb_render converged (-step 0.125 -shadowstep 0.375)", ["vdb_render", path, out, *common, "-step", "0.125", "-shadowstep", "0.375"])]
    configs += [(f"vdb_render {' '.join(a) or 'defaults'}", ["vdb_render", path, out, *common, *a]) for _, a in VDB_CONFIGS]
    configs += [(l, [*EWA_RENDER, path, out, *common, *a]) for l, a in LADDER_EWA]
    print(f"# analytic field ({len(BLOBS)} Gaussian blobs on 64^3 voxels), {args.res} orthographic, gain 0, cutoff 0; "
          "PSNR (RGB) against the integral of the blobs themselves")
    print("| setting | time (s) | PSNR against the truth (dB) |")
    print("|---|---|---|")
    for name, cmd in configs:
        t = timed(cmd, 1)
        print(f"| {name} | {t:.2f} | {diff(out, truth)[1]:.1f} |", flush=True)


def cmd_targets(args):
    """Issue 3's targets: vdb_render's defaults and the three presets, interleaved round by round
    so that the machine's drifting speed hits all of them alike; medians, ratios and PSNR."""
    tmp = tempfile.mkdtemp(prefix="vdb_ewa_targets_")
    label, path, cam = next(s for s in SCENES if s[0] == args.scene)
    common = ["-res", args.res, *cam.split()]
    conv, ref = reference_paths(args.cache, label, args.res)
    if not (os.path.exists(conv) and os.path.exists(ref)):
        print(f"# no reference images in {args.cache}: times only (`bench.py tradeoff --scenes {label} "
              f"--res {args.res} --cache {args.cache}` makes them)")
    configs = [("vdb_render defaults", ["vdb_render", path, os.path.join(tmp, "v.exr"), *common])]
    configs += [(f"quality {q}", [*EWA_RENDER, path, os.path.join(tmp, f"{q}.exr"), *common, "--quality", q])
                for q in ("draft", "default", "high")]
    times = {name: [] for name, _ in configs}
    for _ in range(args.repeat):
        for name, cmd in configs:
            times[name].append(run(cmd)[0])
    base = statistics.median(times["vdb_render defaults"])
    print(f"# {label} {args.res}: median of {args.repeat} interleaved rounds, {os.cpu_count()} cores")
    print("| setting | median time (s) | all times (s) | speed-up vs vdb_render defaults | PSNR vs raymarch (dB) | PSNR vs vdb_render converged (dB) |")
    print("|---|---|---|---|---|---|")
    for name, cmd in configs:
        t = statistics.median(times[name])
        out = next(a for a in cmd if a.endswith(".exr"))
        psnr = [f"{diff(out, r)[1]:.1f}" if os.path.exists(r) else "-" for r in (ref, conv)]
        print(f"| {name} | {t:.2f} | {', '.join(f'{x:.2f}' for x in times[name])} | {base / t:.1f}x | "
              f"{psnr[0]} | {psnr[1]} |", flush=True)


DENSE_BLOCK_CAMERA = "-translate 80,80,400 -lookat 80,80,80"


def dense_block(folder):
    """Issue 37's generated dense block: 160^3 = 4.1M active voxels (voxel size 1, index =
    world), a smooth field between 0.25 and 0.85, opaque like a scan: with the default medium
    (extinction 1.6) a ray keeps under 10 % of its light after 3-5 voxels. Written once into
    @a folder (pyopenvdb); returns its path."""
    path = os.path.join(folder, "dense_block.vdb")
    if os.path.exists(path):
        return path
    # In a process of its own: the renders this bench starts would otherwise inherit its 365 MB
    # (forked, and getrusage's maxrss survives exec).
    script = f"""
import numpy as np, pyopenvdb as vdb
n = 160
x, y, z = np.meshgrid(*(np.arange(n, dtype=np.float64),) * 3, indexing="ij")
values = 0.55 + 0.15 * np.sin(x / 7.0) * np.cos(y / 11.0) + 0.15 * np.sin((y + z) / 9.0) * np.cos(x / 13.0)
grid = vdb.FloatGrid()
grid.copyFromArray(values.astype(np.float32), tolerance=0.0)
grid.name = "density"
grid.gridClass = vdb.GridClass.FOG_VOLUME
vdb.write({path!r}, grids=[grid])
"""
    subprocess.run([sys.executable, "-c", script], check=True)
    return path


def by_level(stdout, noun):
    """-v's count of @a noun ("footprint samples", "slab composites") at each image level:
    every pixel, every 2nd, 4th and 8th (all at every pixel where -v names no level)."""
    m = re.search(rf"(\d+) {noun}(?: \((\d+) at every pixel, (\d+) every 2nd, (\d+) every 4th, (\d+) every 8th)?", stdout)
    return [int(g) for g in m.groups()[1:]] if m.group(2) else [int(m.group(1)), 0, 0, 0]


def interleaved(cmds, repeat):
    """Run each of @a cmds (name -> command) once a round for @a repeat rounds: each one's wall
    times and CPU times (its children's user + system) per round, and its last stdout."""
    wall = {k: [] for k in cmds}
    cpu = {k: [] for k in cmds}
    outs = {}
    for _ in range(repeat):
        for k, c in cmds.items():
            before = os.times()
            dt, outs[k] = run(c)
            after = os.times()
            wall[k].append(dt)
            cpu[k].append(after.children_user + after.children_system - before.children_user - before.children_system)
    return wall, cpu, outs


def views(tmp, res, keep):
    """(label, path, camera, the options that frame it at @a res) for each scene @a keep(label)
    accepts and the generated dense block (written into @a tmp), from the README camera and the
    default one (vdb_render's framing)."""
    scenes = [s for s in SCENES if os.path.exists(s[1]) and keep(s[0])]
    scenes.append(("dense block (generated)", dense_block(tmp), DENSE_BLOCK_CAMERA))
    for label, path, cam in scenes:
        for camera, cargs in (("README", cam.split()), ("default", [])):
            yield label, path, camera, ["-res", res, *cargs]


def cmd_cull(args):
    """The streamed frame: --cull on against --cull off (the whole frame) and vdb_render's
    defaults, interleaved round by round, from each scene's README camera and from the default
    camera (vdb_render's framing); the counters of the streamed frame (bricks, kernels, light-map
    rays marched on demand) and the two images' PSNR."""
    tmp = tempfile.mkdtemp(prefix="vdb_ewa_cull_")
    print(f"# --cull on / off against vdb_render's defaults, {args.res}, median of {args.repeat} interleaved rounds, "
          f"{os.cpu_count()} cores")
    print("| scene | camera | vdb_render (s) | cull off (s) | cull on (s) | on vs off | on vs vdb_render | bricks expanded / hidden / outside "
          "| kernels on / off | light rays marched on | stages on: kernels, shadows, project, rasterise | peak MB on / off | PSNR on vs off (dB) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for label, path, camera, common in views(tmp, args.res, lambda label: "grids/" not in label):
        cmds = {"vdb_render": ["vdb_render", path, os.path.join(tmp, "v.exr"), *common],
                "off": [*EWA_RENDER, path, os.path.join(tmp, "off.exr"), *common, "--cull", "off", "-v"],
                "on": [*EWA_RENDER, path, os.path.join(tmp, "on.exr"), *common, "--cull", "on", "-v"]}
        times, _, outs = interleaved(cmds, args.repeat)
        med = {k: statistics.median(v) for k, v in times.items()}
        m = re.search(r"(\d+) bricks in \d+ depth windows?, (\d+) expanded, (\d+) hidden behind opaque tiles, (\d+) outside", outs["on"])
        bricks = f"{m.group(2)} / {m.group(3)} / {m.group(4)} of {m.group(1)}" if m else "not streamed"
        kernels = [re.search(r"; (\d+) kernels \(", outs[k]).group(1) for k in ("on", "off")]
        lm = re.search(r"light on demand: (\d+) of (\d+) light-map rays marched", outs["on"])
        light = f"{int(lm.group(1)) / int(lm.group(2)):.0%} of {lm.group(2)}" if lm else "all"
        peaks = [re.search(r"peak memory (\d+) MB", outs[k]).group(1) for k in ("on", "off")]
        st = stages(outs["on"])
        psnr = diff(os.path.join(tmp, "on.exr"), os.path.join(tmp, "off.exr"))[1]
        print(f"| {label} | {camera} | {med['vdb_render']:.2f} | {med['off']:.2f} | {med['on']:.2f} | {med['off'] / med['on']:.2f}x | "
              f"{med['vdb_render'] / med['on']:.1f}x | {bricks} | {kernels[0]} / {kernels[1]} | {light} | {st.get('kernels', nan):.3f}, "
              f"{st.get('shadows', nan):.3f}, {st.get('project', nan):.3f}, {st.get('rasterise', nan):.3f} | {peaks[0]} / {peaks[1]} | "
              f"{psnr:.1f} |", flush=True)


def cmd_draft(args):
    """Issue 54's draft: `--quality draft` against `default` and vdb_render's defaults,
    interleaved round by round, float EXRs (vdb_render's file type), from each scene's README
    camera and the default camera; medians, and draft / default as the median of each round's
    ratio (wall and CPU time)."""
    tmp = tempfile.mkdtemp(prefix="vdb_ewa_draft_")
    print(f"# --quality draft against default and vdb_render's defaults, {args.res}, median of {args.repeat} interleaved rounds, "
          f"{os.cpu_count()} cores")
    print("| scene | camera | vdb_render (s) | default (s) | draft (s) | draft / default (wall) | draft / default (CPU) "
          "| default against vdb_render | draft against vdb_render | draft's pixel size | draft stages: kernels, shadows, project, rasterise, write |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for label, path, camera, common in views(tmp, args.res, lambda label: "tiles" not in label):
        cmds = {"vdb_render": ["vdb_render", path, os.path.join(tmp, "v.exr"), *common],
                "default": [*EWA_RENDER, path, os.path.join(tmp, "default.exr"), *common, "-v"],
                "draft": [*EWA_RENDER, path, os.path.join(tmp, "draft.exr"), *common, "--quality", "draft", "-v"]}
        wall, cpu, outs = interleaved(cmds, args.repeat)
        med = {k: statistics.median(v) for k, v in wall.items()}
        ratio = statistics.median([a / b for a, b in zip(wall["draft"], wall["default"])])
        cpu_ratio = statistics.median([a / b for a, b in zip(cpu["draft"], cpu["default"])])
        st = stages(outs["draft"])
        m = re.search(r"one sample a ([0-9.]+)x", outs["draft"])
        size = f"{float(m.group(1)):.2f}" if m else "1"
        print(f"| {label} | {camera} | {med['vdb_render']:.2f} | {med['default']:.2f} | {med['draft']:.2f} | {ratio:.2f}x | {cpu_ratio:.2f}x "
              f"| {med['vdb_render'] / med['default']:.1f}x | {med['vdb_render'] / med['draft']:.1f}x | {size} | "
              + ", ".join(f"{st.get(k, nan):.3f}" for k in ("kernels", "shadows", "project", "rasterise", "write")) + " |", flush=True)


def with_velocity(src, folder, label, spin, rise):
    """@a src's density with a generated velocity grid "v" (world units per second) on its
    active voxels dilated by 2: a rising plume turning about the vertical axis through the
    active box's centre, v = (-spin (z - cz), rise, spin (x - cx)). Written once into @a folder."""
    path = os.path.join(folder, f"{label}_v.vdb")
    if os.path.exists(path):
        return path
    script = f"""
import numpy as np, pyopenvdb as vdb
grids, _ = vdb.readAll({src!r})
density = next(g for g in grids if g.valueTypeName == 'float')
lo, hi = density.evalActiveVoxelBoundingBox()
cw = density.transform.indexToWorld(tuple((a + b) / 2.0 for a, b in zip(lo, hi)))
v = vdb.Vec3SGrid()
v.name = 'v'
v.transform = density.transform
pad = 2
shape = tuple(b - a + 1 + 2 * pad for a, b in zip(lo, hi))
ijk = np.stack(np.meshgrid(*[np.arange(a - pad, b + pad + 1) for a, b in zip(lo, hi)], indexing='ij'), axis=-1).reshape(-1, 3)
o = np.array(density.transform.indexToWorld((0.0, 0.0, 0.0)))
A = np.array([np.array(density.transform.indexToWorld(e)) - o for e in ((1.0, 0, 0), (0, 1.0, 0), (0, 0, 1.0))])
w = ijk @ A + o  # the map is affine
vel = np.stack([-{spin} * (w[:, 2] - cw[2]), np.full(len(w), {rise}), {spin} * (w[:, 0] - cw[0])], axis=-1).astype(np.float32)
# Only on the density's active voxels dilated by pad (a cube of 2 pad + 1 a side): elsewhere
# the background (0), inactive, as a sparse simulation's velocity field.
active = np.zeros(shape, dtype=bool)
for item in density.iterOnValues():
    a0 = np.array(item['min']) - np.array(lo) + pad
    a1 = np.array(item['max']) - np.array(lo) + pad + 1
    active[a0[0]:a1[0], a0[1]:a1[1], a0[2]:a1[2]] = True
grown = np.zeros_like(active)
for dx in range(-pad, pad + 1):
    for dy in range(-pad, pad + 1):
        for dz in range(-pad, pad + 1):
            grown |= np.roll(active, (dx, dy, dz), axis=(0, 1, 2))
vel = vel.reshape(shape + (3,))
vel[~grown] = 0.0
v.copyFromArray(vel, ijk=tuple(a - pad for a in lo), tolerance=(0.0, 0.0, 0.0))
vdb.write({path!r}, grids=[density, v])
"""
    subprocess.run([sys.executable, "-c", script], check=True)
    return path


def with_and_without(path, common, opts, tmp, repeat):
    """Render @a path with and without @a opts in @a repeat interleaved rounds: the median times
    {"with": s, "without": s} and the two images' paths."""
    out_with, out_without = os.path.join(tmp, "with.exr"), os.path.join(tmp, "without.exr")
    cmds = {"with": [*EWA_RENDER, path, out_with, *common, *opts], "without": [*EWA_RENDER, path, out_without, *common]}
    times = {k: [] for k in cmds}
    for _ in range(repeat):
        for k, c in cmds.items():
            times[k].append(run(c)[0])
    return {k: statistics.median(v) for k, v in times.items()}, out_with, out_without


BLUR_SCENES = [("pyro", f"{ASSETS}/pyro.vdb", "-translate 0.225,2.175,15.75 -lookat 0.225,2.175,-0.225", 3.0, 10.0),
               ("cloud (grids/)", f"{ROOT}/grids/cloud.vdb", "-translate 1.5,0.8,4.5 -lookat 0,0,0", 1.5, 3.0)]


def cmd_blur(args):
    """Issue 38's motion blur and depth of field: on pyro and the sample cloud, each with a generated
    velocity grid (with_velocity), `default` and `high` against our reference integrator with
    --blur-samples shutter times and lens points (the converged image: vdb_render has neither),
    and each frame's time against the same frame without the effect, interleaved round by round."""
    tmp = args.keep or tempfile.mkdtemp(prefix="vdb_ewa_blur_")
    os.makedirs(tmp, exist_ok=True)
    print(f"# {args.res}, median of {args.repeat} interleaved rounds, {os.cpu_count()} cores; reference: --method raymarch "
          f"--step {args.ref_step} --shadowstep {args.ref_step} --blur-samples {args.ref_samples}")
    print("| scene | effect | quality | time with (s) | time without (s) | with / without | PSNR vs reference (dB) | PSNR of the frame without (dB) |")
    print("|---|---|---|---|---|---|---|---|")
    for label, src, cam, spin, rise in BLUR_SCENES:
        if not os.path.exists(src):
            continue
        key = label.split()[0]
        path = with_velocity(src, tmp, key, spin, rise)
        common = ["-res", args.res, *cam.split()]
        focus = float(cam.split()[1].split(",")[2]) - float(cam.split()[3].split(",")[2])  # eye z - target z
        effects = [("motion blur", ["--velocity-grid", "v"]),
                   ("depth of field", ["--fstop", str(args.fstop), "--focus-distance", f"{0.8 * focus:g}"])]
        for effect, opts in effects:
            ref = os.path.join(tmp, f"{key}_{effect.replace(' ', '_')}_{args.res}_ref.exr")
            if not os.path.exists(ref):
                run([*EWA_RENDER, path, ref, *common, *opts, "--method", "raymarch", "--step", str(args.ref_step),
                     "--shadowstep", str(args.ref_step), "--blur-samples", str(args.ref_samples)])
            for q in ("default", "high"):
                t, out_with, out_without = with_and_without(path, common + ["--quality", q], opts, tmp, args.repeat)
                print(f"| {label} | {effect} | {q} | {t['with']:.2f} | {t['without']:.2f} | {t['with'] / t['without']:.2f}x | "
                      f"{diff(out_with, ref)[1]:.1f} | {diff(out_without, ref)[1]:.1f} |", flush=True)


LIGHT_SCENES = [
    # (label, file, camera, optical model and the directional light, [(light, options)])
    ("pyro, thin (--scatter 0.05)", f"{ASSETS}/pyro.vdb", "-translate 0.225,2.175,15.75 -lookat 0.225,2.175,-0.225",
     "--scatter 0.05 --absorb 0.01 --light 0.3,0.3,0,0.2,0.2,0.2",
     [("point light inside", "--point-light 0.225,2.5,-0.225,6,3,1.2"),
      ("spot light", "--spot-light -6,6,8,0.225,2.5,-0.225,25,0.3,120,120,140")]),
    ("pyro, vdb_render's model", f"{ASSETS}/pyro.vdb", "-translate 0.225,2.175,15.75 -lookat 0.225,2.175,-0.225",
     "--light 0.3,0.3,0,0.2,0.2,0.2",
     [("spot light", "--spot-light -6,6,8,0.225,2.5,-0.225,25,0.3,60,60,70")]),
    ("cloud (grids/)", f"{ROOT}/grids/cloud.vdb", "-translate 1.5,0.8,4.5 -lookat 0,0,0", "--light 0.3,0.3,0,0.3,0.3,0.3",
     [("point light inside", "--point-light 0,0,0,0.4,0.2,0.08"),
      ("spot light", "--spot-light 3,2,1,0,0,0,20,0.3,10,10,12")]),
]


def cmd_lights(args):
    """Point and spot lights: `default` and `high` against our reference integrator (shadow rays
    from every sample to the light; vdb_render has no point lights), and each frame's time against
    the same frame with its directional light only, interleaved round by round."""
    tmp = args.keep or tempfile.mkdtemp(prefix="vdb_ewa_lights_")
    os.makedirs(tmp, exist_ok=True)
    print(f"# {args.res}, median of {args.repeat} interleaved rounds, {os.cpu_count()} cores; reference: --method raymarch "
          f"--step {args.ref_step} --shadowstep {args.ref_step}")
    print("| scene | light | quality | time with (s) | time without (s) | with / without | PSNR vs reference (dB) |")
    print("|---|---|---|---|---|---|---|")
    for n, (label, src, cam, model, lights) in enumerate(LIGHT_SCENES):
        if not os.path.exists(src):
            continue
        common = ["-res", args.res, *cam.split(), *model.split()]
        for k, (light, opts) in enumerate(lights):
            ref = os.path.join(tmp, f"lights_{n}_{k}_{args.res}_ref.exr")
            if not os.path.exists(ref):
                run([*EWA_RENDER, src, ref, *common, *opts.split(), "--method", "raymarch", "--step", str(args.ref_step),
                     "--shadowstep", str(args.ref_step)])
            for q in ("default", "high"):
                t, out_with, _ = with_and_without(src, common + ["--quality", q], opts.split(), tmp, args.repeat)
                print(f"| {label} | {light} | {q} | {t['with']:.2f} | {t['without']:.2f} | {t['with'] / t['without']:.2f}x | "
                      f"{diff(out_with, ref)[1]:.1f} |", flush=True)


def cmd_volumes(args):
    """Several volumes in one sweep: the shared pyro with the sample cloud (moved into its lower
    half: they interpenetrate) added by --add-volume, `default` and `high` against our reference
    integrator of the summed field, and the time against pyro alone, interleaved round by round."""
    tmp = args.keep or tempfile.mkdtemp(prefix="vdb_ewa_volumes_")
    os.makedirs(tmp, exist_ok=True)
    pyro, cloud = f"{ASSETS}/pyro.vdb", os.path.join(tmp, "cloud_moved.vdb")
    if not os.path.exists(pyro):
        sys.exit(f"{pyro} is missing")
    if not os.path.exists(cloud):  # the cloud, twice its size, its centre 1.5 world units up in pyro's plume
        script = f"""
import pyopenvdb as vdb
g = vdb.read({ROOT + '/grids/cloud.vdb'!r}, 'density')
m = g.transform.indexToWorld
o = m((0, 0, 0))
g.transform = vdb.createLinearTransform([[2 * (a - b) for a, b in zip(m(e), o)] + [0] for e in ((1, 0, 0), (0, 1, 0), (0, 0, 1))]
                                        + [[0.2, 1.5, 0.0, 1]])
vdb.write({cloud!r}, grids=[g])
"""
        subprocess.run([sys.executable, "-c", script], check=True)
    common = ["-res", args.res, *"-translate 0.225,2.175,15.75 -lookat 0.225,2.175,-0.225".split()]
    # The cloud with the input's medium, and with one of its own: a brighter, bluish scatterer
    # (extinction 2.1 in every channel against pyro's 1.6, albedo 0.86-0.95).
    own = ["--absorb", "0.3,0.2,0.1", "--scatter", "1.8,1.9,2.0"]
    scenes = [("pyro + cloud, interpenetrating", ["--add-volume", cloud], [], "volumes"),
              ("pyro + cloud of its own medium", ["--add-volume", cloud, "--add-volume-material", "absorb=0.3,0.2,0.1 scatter=1.8,1.9,2.0"],
               own, "volumes_own")]
    print(f"# {args.res}, median of {args.repeat} interleaved rounds, {os.cpu_count()} cores; reference: --method raymarch "
          f"--step {args.ref_step} --shadowstep {args.ref_step} of the volumes in one field")
    print("| scene | quality | time with (s) | time without (s) | with / without | PSNR vs reference (dB) | PSNR of over (dB) |")
    print("|---|---|---|---|---|---|---|")
    for name, opts, cloud_medium, tag in scenes:
        ref = os.path.join(tmp, f"{tag}_{args.res}_ref.exr")
        if not os.path.exists(ref):
            run([*EWA_RENDER, pyro, ref, *common, *opts, "--method", "raymarch", "--step", str(args.ref_step), "--shadowstep", str(args.ref_step)])
        for q in ("default", "high"):
            t, out_with, out_without = with_and_without(pyro, common + ["--quality", q], opts, tmp, args.repeat)
            # The cloud alone, composited over pyro and under it: separate renders cannot interpenetrate.
            alone = os.path.join(tmp, "cloud_alone.exr")
            run([*EWA_RENDER, cloud, alone, *common, "--quality", q, *cloud_medium])
            overs = []
            for front, back in ((alone, out_without), (out_without, alone)):
                comp = os.path.join(tmp, "over.exr")
                subprocess.run(["oiiotool", front, back, "--over", "-o", comp], check=True, capture_output=True)
                overs.append(diff(comp, ref)[1])
            print(f"| {name} | {q} | {t['with']:.2f} | {t['without']:.2f} | {t['with'] / t['without']:.2f}x | "
                  f"{diff(out_with, ref)[1]:.1f} | {max(overs):.1f} (the better order) |", flush=True)


# Scale: each scene seen so that its voxels span a given number of pixels, from the README
# camera's direction: (label, file, voxel size, target, direction towards the eye).
SCALE_SCENES = [
    ("cloud (grids/)", f"{ROOT}/grids/cloud.vdb", 0.04, (0.0, 0.0, 0.0), (1.5, 0.8, 4.5)),
    ("smoke", f"{ASSETS}/smoke.vdb", 0.4762, (-7.381, 40.48, 0.4762), (0.0, 0.0, 1.0)),
    ("pyro", f"{ASSETS}/pyro.vdb", 0.075, (0.225, 2.175, -0.225), (0.0, 0.0, 1.0)),
    ("pig", f"{ASSETS}/pig.vdb", 0.005, (0.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
]
SCALE_MEDIA = [("vdb_render's model", ["--scatter", "0.5", "--absorb", "0.05"]),
               ("thick, physical shadows", ["--scatter", "2", "--gain", "0"])]
SCALE_SETTINGS = [("default --supersample 1", ["--supersample", "1"]), ("draft", ["--quality", "draft"]),
                  ("default", []), ("high", ["--quality", "high"]), ("final", ["--quality", "final"])]


def scale_camera(res, voxel, target, direction, px):
    """The camera options at @a res looking at @a target from @a direction, at the distance
    where a voxel of @a voxel world units spans @a px pixels (vdb_render's default 50 mm lens)."""
    w = int(res.split("x")[0])
    focal = w * 50.0 / 41.2136  # pixels: vdb_render's default 50 mm lens on a 41.2136 mm film back
    n = sum(d * d for d in direction) ** 0.5
    dist = voxel * focal / px
    eye = ",".join(f"{t + d / n * dist:.6g}" for t, d in zip(target, direction))
    return ["-res", res, "-translate", eye, "-lookat", ",".join(f"{t:.6g}" for t in target)]


def scale_metrics(out, ref):
    """(PSNR over RGB, peak 1; brightness: sum of RGB over the reference's; alpha IoU at 0.05)
    over the reference's footprint: its pixels of alpha above 1e-3 and 2 more around, so that
    the empty frame around a small volume does not dilute the figures."""
    import numpy as np
    import OpenImageIO as oiio

    def read(path):  # ImageInput, not ImageBuf: the image cache would hand back the last o.exr
        image = oiio.ImageInput.open(path)
        spec = image.spec()
        pixels = np.asarray(image.read_image(format="float")).reshape(spec.height, spec.width, spec.nchannels)
        image.close()
        return np.stack([pixels[..., list(spec.channelnames).index(c)] for c in "RGBA"], axis=-1)

    a, b = read(out), read(ref)
    ys, xs = np.nonzero(b[..., 3] > 1e-3)
    if len(ys):
        sl = np.s_[max(ys.min() - 2, 0):ys.max() + 3, max(xs.min() - 2, 0):xs.max() + 3]
        a, b = a[sl], b[sl]
    mse = float(((a[..., :3] - b[..., :3]) ** 2).mean())
    psnr = 10 * np.log10(1.0 / mse) if mse > 0 else float("inf")
    bright = float(a[..., :3].sum() / max(b[..., :3].sum(), 1e-30))
    ma, mb = a[..., 3] > 0.05, b[..., 3] > 0.05
    return psnr, bright, float((ma & mb).sum() / max((ma | mb).sum(), 1)), a.shape[1], a.shape[0]


def cmd_scale(args):
    """Issue 52: every preset where voxels look small, against the reference integrator
    supersampled (--pixel-samples: 16 rays a pixel, 256 where a voxel spans under half a pixel and
    1024 under a fifth, where footprints are a few dozen pixels and 64 rays left the wisps' alpha
    noisy at 0.05;
    --step 0.25, --shadowstep 0.375, vdb_render's converged model), on the sample cloud and the
    shared assets, seen from the README camera's direction at the distance where a voxel spans
    PX pixels; two media: vdb_render's model, and a thick one with physical shadows. Time of
    each setting against vdb_render's defaults on the same camera, in the same run."""
    tmp = tempfile.mkdtemp(prefix="vdb_ewa_scale_")
    print(f"# {args.res}: median of {args.repeat} runs a setting, {os.cpu_count()} cores; reference: --method raymarch "
          "--step 0.25 --shadowstep 0.375 --pixel-samples 16 (256 below half a pixel a voxel, 1024 below a fifth); figures over the reference's footprint")
    print("| scene | medium | voxel (px) | setting | PSNR (dB) | brightness | alpha IoU | time / vdb_render defaults |")
    print("|---|---|---|---|---|---|---|---|")
    wanted = None if args.scenes == "all" else args.scenes.split(",")
    for label, path, voxel, target, direction in SCALE_SCENES:
        if (wanted and label.split()[0] not in wanted) or not os.path.exists(path):
            continue
        for px in (float(p) for p in args.px.split(",")):
            camera = scale_camera(args.res, voxel, target, direction, px)
            for medium, model in SCALE_MEDIA:
                if args.media != "all" and ("thick" if "thick" in medium else "thin") not in args.media.split(","):
                    continue
                ref = os.path.join(tmp, "ref.exr")
                run([*EWA_RENDER, path, ref, *camera, *model, "--method", "raymarch", "--step", "0.25", "--shadowstep", "0.375",
                     "--pixel-samples", "1024" if px < 0.2 else "256" if px < 0.5 else "16"])
                peer = timed(["vdb_render", path, os.path.join(tmp, "peer.exr"), *camera,
                              *(a.replace("--", "-") for a in model)], args.repeat)
                for name, extra in SCALE_SETTINGS:
                    out = os.path.join(tmp, "o.exr")
                    t = timed([*EWA_RENDER, path, out, *camera, *model, *extra], args.repeat)
                    psnr, bright, iou, cw, ch = scale_metrics(out, ref)
                    print(f"| {label} | {medium} | {px:g} | {name} | {psnr:.1f} | {100 * (bright - 1):+.1f} % | {iou:.3f} | "
                          f"{t / peer:.2f} |", flush=True)


def tile_grid(path, last, value, voxel=1.0):
    """A fog grid of active tiles filling [0, last]^3 (pyopenvdb makes the largest tiles that fit)."""
    import pyopenvdb as vdb
    g = vdb.FloatGrid()
    g.name = "density"
    g.gridClass = vdb.GridClass.FOG_VOLUME
    g.transform = vdb.createLinearTransform(voxelSize=voxel)
    g.fill((0, 0, 0), (last, last, last), value, True)
    vdb.write(path, grids=[g])


def cmd_tiles(args):
    """Issue 52, in time: files of active tiles seen from afar at 160x90 (512 root tiles of
    4096^3 voxels from 90,000 units, also of value 1e30; 16^3 internal tiles of 128^3 from
    12,000), time and peak memory of each preset; then a cube of 2^3 tiles of 128^3 voxels
    (density 0.05, 0.01 units a voxel, optical depth 20 across) from 20, 80 and 300 units at
    480x270 against the reference integrator (16 rays a pixel), and against the lattice seen
    large (--lod 1e-3: --tile-spacing at every distance, no sub-pixels for tiles)."""
    tmp = tempfile.mkdtemp(prefix="vdb_ewa_tiles_")
    print(f"# {os.cpu_count()} cores; one run each")
    print("| file | camera | setting | time (s) | peak (MB) | kernels | sub-pixels |")
    print("|---|---|---|---|---|---|---|")
    hostile = [("512 root tiles of 4096^3, 0.5", 32767, 0.5, 90000.0), ("512 root tiles of 4096^3, 1e30", 32767, 1e30, 90000.0),
               ("16^3 tiles of 128^3, 0.5", 2047, 0.5, 12000.0)]
    for label, last, value, dist in hostile:
        path = os.path.join(tmp, "tiles.vdb")
        tile_grid(path, last, value)
        c = (last + 1) / 2.0
        camera = ["-res", "160x90", "-translate", f"{c:g},{c:g},{last + 1 + dist:g}", "-lookat", f"{c:g},{c:g},{c:g}"]
        dt, peak, _, _ = timed_peak(["vdb_render", path, os.path.join(tmp, "peer.exr"), *camera])
        print(f"| {label} | {dist:g} units | vdb_render defaults | {dt:.2f} | {peak:.0f} | - | - |", flush=True)
        for name, extra in (("default", []), ("draft", ["--quality", "draft"]), ("final", ["--quality", "final"])):
            dt, peak, out, code = timed_peak([*EWA_RENDER, path, os.path.join(tmp, "o.exr"), *camera, *extra, "-v"])
            kernels = re.search(r"; (\d+) kernels", out)
            sub = re.search(r"composited at (\d+)x\d+ sub-pixels", out)
            print(f"| {label} | {dist:g} units | {name} | {dt:.2f} | {peak:.0f} | {kernels.group(1) if kernels else '-'} | "
                  f"{sub.group(1) if sub else 1} |", flush=True)
    path = os.path.join(tmp, "cube.vdb")
    tile_grid(path, 255, 0.05, 0.01)
    print()
    print("| cube of 2^3 tiles | setting | PSNR (dB) | brightness | alpha IoU | time / vdb_render defaults |")
    print("|---|---|---|---|---|---|")
    for dist in (20, 80, 300):
        camera = ["-res", "480x270", "-translate", f"1.28,1.28,{1.28 + dist:g}", "-lookat", "1.28,1.28,1.28"]
        ref = os.path.join(tmp, "ref.exr")
        run([*EWA_RENDER, path, ref, *camera, "--method", "raymarch", "--pixel-samples", "16"])
        peer = timed(["vdb_render", path, os.path.join(tmp, "peer.exr"), *camera], 1)
        for name, extra in (("lattice seen large (--lod 1e-3)", ["--lod", "1e-3"]), ("default", []), ("final", ["--quality", "final"])):
            out = os.path.join(tmp, "o.exr")
            t = timed([*EWA_RENDER, path, out, *camera, *extra], 1)
            psnr, bright, iou, _, _ = scale_metrics(out, ref)
            print(f"| {dist} units | {name} | {psnr:.1f} | {100 * (bright - 1):+.1f} % | {iou:.3f} | {t / peer:.2f} |", flush=True)


def cmd_python(args):
    label, path, camera = next(s for s in SCENES if s[0] == args.scene)
    pythonpath = os.environ.get("VDB_EWA_PYTHONPATH", os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(EWA))), "python"))
    cam = camera.split()
    keywords = ", ".join("%s=%r" % (cam[i][1:], tuple(float(x) for x in cam[i + 1].split(","))) for i in range(0, len(cam), 2))
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.exr")
        script = ("import time; t0 = time.perf_counter(); import vdb_ewa; frame = vdb_ewa.render(%r, res=%r, exr_type='float', %s); "
                  "a = frame.beauty; t1 = time.perf_counter(); %s print(t1 - t0)") % (
                      path, args.res, keywords, "vdb_ewa.set_exr_threads(0); frame.write(%r);" % out if args.write else "")
        python = ["/usr/bin/python3", "-c", script]
        cli = EWA_RENDER + [path, out, "--res", args.res] + cam
        peer = ["vdb_render", path, out, "-res", args.res] + cam
        env = dict(os.environ, PYTHONPATH=pythonpath)
        rows = {"vdb_render": [], "vdb_ewa CLI": [], "python process": [], "python import to array": []}
        for _ in range(args.repeat):  # interleaved rounds: the machine's drift hits all alike
            rows["vdb_render"].append(run(peer)[0])
            rows["vdb_ewa CLI"].append(run(cli)[0])
            t0 = time.perf_counter()
            p = subprocess.run(python, capture_output=True, text=True, env=env)
            rows["python process"].append(time.perf_counter() - t0)
            if p.returncode != 0:
                sys.exit(p.stderr)
            rows["python import to array"].append(float(p.stdout.split()[-1]))
    med = {k: statistics.median(v) for k, v in rows.items()}
    print(f"{label} at {args.res}, median of {args.repeat} interleaved rounds{' (python writes the EXR too)' if args.write else ''}:")
    print(f"{'':26s} {'seconds':>8s} {'/ CLI':>7s} {'/ vdb_render':>13s}")
    for k, v in med.items():
        print(f"{k:26s} {v:8.3f} {v / med['vdb_ewa CLI']:7.3f} {v / med['vdb_render']:13.3f}")


def scene_script(args, name, body):
    """Run @a body (Python, with grid, opts, before and after, the README camera and the one an
    orbit of 10 degrees away, in scope) in a fresh Python process with the vdb_ewa module;
    @return the JSON it printed last."""
    pythonpath = os.environ.get("VDB_EWA_PYTHONPATH", os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(EWA))), "python"))
    label, path, camera = next(s for s in SCENES if s[0] == name)
    keywords = lambda words: dict((words[i][1:], tuple(float(x) for x in words[i + 1].split(","))) for i in range(0, len(words), 2))
    before, after = keywords(camera_path(camera, "orbit", 0, 1)), keywords(camera_path(camera, "orbit", 10, 1))
    script = f"""
import json, statistics, time, vdb_ewa
grid = vdb_ewa.open({path!r})
opts = dict(res={args.res!r}, quality={args.quality!r})
before, after = {before!r}, {after!r}
""" + body
    p = subprocess.run(["/usr/bin/python3", "-c", script], capture_output=True, text=True, env=dict(os.environ, PYTHONPATH=pythonpath))
    if p.returncode != 0:
        sys.exit(p.stderr)
    return label, json.loads(p.stdout.split("\n")[-2])


def cmd_scene(args):
    """Issue 55's camera move: vdb_ewa.Scene.render after a render from a camera 10 degrees away on
    an orbit, against vdb_ewa.render of the same frame in the same process (the grid opened once
    for both: neither pays for loading), interleaved rounds, medians."""
    rows = []
    for name in args.scenes.split(","):
        label, (cold, warm, ws, cs) = scene_script(args, name, f"""
cold, warm, stats = [], [], None
for _ in range({args.repeat}):
    t0 = time.perf_counter(); c = vdb_ewa.render(grid, **opts, **after); cold.append(time.perf_counter() - t0)
    scene = vdb_ewa.Scene(grid, **opts)
    scene.render(**before)
    t0 = time.perf_counter(); w = scene.render(**after); warm.append(time.perf_counter() - t0)
    assert (w.beauty == c.beauty).all(), "the scene's frame is not the cold render's"
    stats = (w.stats, c.stats)
print(json.dumps([statistics.median(cold), statistics.median(warm), stats[0], stats[1]]))
""")
        rows.append((label, cold, warm, ws, cs))
    print(f"# vdb_ewa.Scene: a camera move (an orbit of 10 degrees about the README camera's look-at point) against a cold "
          f"in-process render of the same frame, {args.res}, --quality {args.quality}, median of {args.repeat} interleaved rounds; "
          f"the frames are equal bit for bit")
    print("| scene | cold render (s) | scene after a move (s) | scene / cold | light maps kept | light rays marched: cold, scene (kept) | "
          "shadows (s): cold, scene |")
    print("|---|---|---|---|---|---|---|")
    for label, cold, warm, ws, cs in rows:
        print(f"| {label} | {cold:.3f} | {warm:.3f} | {warm / cold:.2f}x | {ws['light_maps_reused']} | {cs['light_rays_marched']}, "
              f"{ws['light_rays_marched']} ({ws['light_rays_reused']}) | {cs['shadow_seconds']:.3f}, {ws['shadow_seconds']:.3f} |")


def cmd_progressive(args):
    """Issue 55's progressive render: Scene.render(progressive=...) of the README camera in a new
    scene (cold: the light maps made) and after an orbit of 10 degrees (warm); seconds from the
    call to the coarse image and to the asked one, against a cold in-process render of the same
    frame (vdb_ewa.render; the grid opened once for all), interleaved rounds, medians."""
    rows = []
    for name in args.scenes.split(","):
        label, row = scene_script(args, name, f"""
times = {{"render": [], "cold coarse": [], "cold asked": [], "warm coarse": [], "warm asked": []}}
rays = None
for _ in range({args.repeat}):
    t0 = time.perf_counter(); c = vdb_ewa.render(grid, **opts, **after); times["render"].append(time.perf_counter() - t0)
    scene = vdb_ewa.Scene(grid, **opts)
    for when, view in (("cold", before), ("warm", after)):
        seen = []
        t0 = time.perf_counter()
        scene.render(progressive=lambda f: seen.append((time.perf_counter() - t0, f.stats["light_rays_marched"])), **view)
        times[when + " coarse"].append(seen[0][0]); times[when + " asked"].append(seen[1][0])
        if when == "cold":
            rays = (seen[0][1], seen[1][1])
print(json.dumps([{{k: statistics.median(v) for k, v in times.items()}}, rays]))
""")
        rows.append((label, row))
    print(f"# vdb_ewa.Scene.render(progressive=...): seconds from the call to the coarse image and to the asked one, {args.res}, "
          f"--quality {args.quality}; cold: a new scene's first render (README camera), warm: after an orbit of 10 degrees; "
          f"against vdb_ewa.render of the same frame in the same process; median of {args.repeat} interleaved rounds")
    print("| scene | render (s) | cold: coarse, asked (s) | warm: coarse, asked (s) | warm coarse / render | light rays a cold scene marches: "
          "coarse, asked |")
    print("|---|---|---|---|---|---|")
    for label, (t, rays) in rows:
        print(f"| {label} | {t['render']:.3f} | {t['cold coarse']:.3f}, {t['cold asked']:.3f} | {t['warm coarse']:.3f}, {t['warm asked']:.3f} | "
              f"{t['warm coarse'] / t['render']:.2f}x | {rays[0]}, {rays[1]} |")


def cmd_soak(args):
    """Issue 55's memory soak: one scene, --moves camera moves (an orbit, 3.6 degrees a move);
    the process's resident memory (/proc/self/statm, after malloc_trim) after the first move
    and every tenth, its peak against a cold render's, and after the scene is released, beside
    the same process after cold renders alone (before the scene and after it: a frame's
    resident memory varies by 10-20 MB with what it sees)."""
    for name in args.scenes.split(","):
        label, (cold_peak, moves, levels, peak) = scene_script(args, name, f"""
import ctypes, gc, math, resource
def resident():
    ctypes.CDLL("libc.so.6").malloc_trim(0)  # what malloc keeps for later goes back first
    return int(open("/proc/self/statm").read().split()[1]) * resource.getpagesize() / 2**20
c = vdb_ewa.render(grid, **opts, **before)
cold_peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
for view in (after, before):  # the process's own growth over its first renders (thread arenas, pools)
    c = vdb_ewa.render(grid, **opts, **view)
del c
levels = [resident()]
scene = vdb_ewa.Scene(grid, **opts)
eye, at = before["translate"], before["lookat"]
r, h = math.hypot(eye[0] - at[0], eye[2] - at[2]), math.atan2(eye[0] - at[0], eye[2] - at[2])
moves = []
for k in range({args.moves}):
    a = h + math.radians(3.6 * k)
    scene.render(translate=(at[0] + r * math.sin(a), eye[1], at[2] + r * math.cos(a)), lookat=at)
    if k == 0 or (k + 1) % 10 == 0:
        moves.append((k + 1, resident()))
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
del scene; gc.collect()
levels.append(resident())
for view in (after, before):
    vdb_ewa.render(grid, **opts, **view)
levels.append(resident())
print(json.dumps([cold_peak, moves, levels, peak]))
""")
        print(f"# {label}: one vdb_ewa.Scene, {args.moves} camera moves (3.6 degrees each), {args.res}, --quality {args.quality}")
        print(f"a cold render's peak: {cold_peak:.0f} MB; the scene's: {peak:.0f} MB ({peak / cold_peak:.2f}x)")
        print("resident after move: " + ", ".join(f"{k}: {mb:.0f} MB" for k, mb in moves))
        print(f"resident after three cold renders, before the scene: {levels[0]:.0f} MB; after the scene is released: {levels[1]:.0f} MB; "
              f"after two more cold renders: {levels[2]:.0f} MB")


def cmd_turntable(args):
    """Issue 55's turntable: 24 frames orbiting one cache (15 degrees a frame about the README
    camera's look-at point, keyed in a --camera-file), rendered as one sequence (`--frames 1-24`,
    one scene: the grid read once, the light kept) against 24 separate processes of one frame
    each, and against the same sequence read from a file per frame (one process, a Renderer per
    frame, as before scenes); wall-clock seconds a frame, interleaved rounds, medians."""
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.scenes.split(","):
            label, path, camera = next(s for s in SCENES if s[0] == name)
            keys = []
            for f in range(1, args.frames + 1):
                words = camera_path(camera, "orbit", 15 * (f - 1), args.frames)
                keys.append({"at": f, "translate": [float(x) for x in words[1].split(",")], "lookat": [float(x) for x in words[3].split(",")]})
            orbit = os.path.join(tmp, "orbit.json")
            with open(orbit, "w") as f:
                json.dump({"keys": keys}, f)
            for f in range(1, args.frames + 1):
                link = os.path.join(tmp, "copy.%04d.vdb" % f)
                if os.path.lexists(link):
                    os.remove(link)
                os.symlink(path, link)
            common = ["--res", args.res, "--quality", args.quality, "--camera-file", orbit]
            frames = "1-%d" % args.frames
            scene = [EWA, path, os.path.join(tmp, "s.####.exr"), "--frames", frames, "-q"] + common
            files = [EWA, os.path.join(tmp, "copy.####.vdb"), os.path.join(tmp, "f.####.exr"), "--frames", frames, "-q"] + common
            times = {"scene": [], "files": [], "processes": []}
            for _ in range(args.repeat):
                times["scene"].append(run(scene)[0])
                times["files"].append(run(files)[0])
                t = 0.0
                for f in range(1, args.frames + 1):
                    t += run([EWA, path, os.path.join(tmp, "p.%04d.exr" % f), "--frames", str(f), "-q"] + common)[0]
                times["processes"].append(t)
            med = {k: statistics.median(v) / args.frames for k, v in times.items()}
            rows.append((label, med))
    print(f"# A {args.frames}-frame turntable of one cache (15 degrees a frame about the README camera's look-at point), {args.res}, "
          f"--quality {args.quality}, half zip EXRs, wall-clock seconds a frame, median of {args.repeat} interleaved rounds")
    print("| scene | separate processes (s/frame) | a file per frame, one process (s/frame) | one scene (s/frame) | one scene against separate processes | "
          "against a file per frame |")
    print("|---|---|---|---|---|---|")
    for label, med in rows:
        print(f"| {label} | {med['processes']:.3f} | {med['files']:.3f} | {med['scene']:.3f} | {med['processes'] / med['scene']:.2f}x faster | "
              f"{med['files'] / med['scene']:.2f}x faster |")


def cmd_imagelod(args):
    """Image-space level of detail (--image-lod): each scene at --image-lod off and each asked
    value (a trailing "c": with --image-lod-composite on), interleaved round by round; the
    footprint samples and slab composites at each level (-v), the median frame time and CPU
    time against off in the same rounds, and the PSNR against off."""
    tmp = tempfile.mkdtemp(prefix="vdb_ewa_imagelod_")
    values = args.values.split(",")
    print(f"# --image-lod against off, {args.res}, default preset, median of {args.repeat} interleaved rounds, "
          f"{os.cpu_count()} cores")
    print("| scene | camera | --image-lod | footprint samples (M): every pixel / 2nd / 4th / 8th "
          "| slab composites (M): every pixel / 2nd / 4th / 8th | frame (s) | against off | CPU against off | PSNR against off (dB) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for label, path, camera, common in views(tmp, args.res, lambda label: "tiles" not in label):
        if camera == "default" and "fog_tommy" not in label:
            continue  # the inside of a volume: the one default camera that magnifies
        settings = ["off", *values]
        cmds = {}
        for v in settings:
            lod = ["--image-lod", v[:-1], "--image-lod-composite", "on"] if v.endswith("c") else ["--image-lod", v, "--image-lod-composite", "off"]
            cmds[v] = [*EWA_RENDER, path, os.path.join(tmp, f"{v}.exr"), *common, *lod, "-v"]
        wall, cpu, outs = interleaved(cmds, args.repeat)
        counts = {v: by_level(outs[v], "footprint samples") for v in settings}
        composites = {v: by_level(outs[v], "slab composites") for v in settings}
        for v in settings:
            psnr = "" if v == "off" else f"{diff(os.path.join(tmp, f'{v}.exr'), os.path.join(tmp, 'off.exr'))[1]:.1f}"
            ratio = statistics.median([a / b for a, b in zip(wall[v], wall["off"])])
            cpu_ratio = statistics.median([a / b for a, b in zip(cpu[v], cpu["off"])])
            levels = " / ".join(f"{c / 1e6:.1f}" for c in counts[v])
            composited = " / ".join(f"{c / 1e6:.2f}" for c in composites[v])
            print(f"| {label} | {camera} | {v} | {levels} | {composited} | {statistics.median(wall[v]):.2f} | {ratio:.2f}x "
                  f"| {cpu_ratio:.2f}x | {psnr} |", flush=True)


def cmd_imagelod_scale(args):
    """Issue 54: image-space level of detail at both ends of scale. Each SCALE_SCENES scene from
    its README camera's direction at the distance where a voxel spans PX pixels, in both media
    (vdb_render's model; thick with physical shadows), at `default` with `--image-lod off`
    and with --image-lod 4, 2 and 1 (composited at the levels, --image-lod-composite on): the
    composites at each level (-v), and PSNR and brightness (sum of RGB) against off. Where no
    footprint is wide enough the image is off's bit for bit."""
    tmp = tempfile.mkdtemp(prefix="vdb_ewa_imagelod_scale_")
    print(f"# {args.res}, default preset; each --image-lod N composited at the levels, against --image-lod off")
    print("| scene | medium | voxel (px) | --image-lod | slab composites (M): every pixel / 2nd / 4th / 8th | PSNR against off (dB) | brightness against off |")
    print("|---|---|---|---|---|---|---|")
    import numpy as np
    import OpenImageIO as oiio
    def rgb(path):
        return oiio.ImageBuf(path).get_pixels(oiio.FLOAT)[..., :3].astype(np.float64)
    for label, path, voxel, target, direction in SCALE_SCENES:
        if not os.path.exists(path) or label.startswith("pig"):
            continue
        for px in (float(p) for p in args.px.split(",")):
            camera = scale_camera(args.res, voxel, target, direction, px)
            for medium, model in SCALE_MEDIA:
                off = os.path.join(tmp, "off.exr")
                run([*EWA_RENDER, path, off, *camera, *model, "--image-lod", "off"])
                ref = rgb(off)
                for v in args.values.split(","):
                    out = os.path.join(tmp, "lod.exr")
                    _, stdout = run([*EWA_RENDER, path, out, *camera, *model, "--image-lod", v, "--image-lod-composite", "on", "-v"])
                    levels = by_level(stdout, "slab composites")
                    img = rgb(out)
                    mse = float(np.mean((img - ref) ** 2))
                    psnr = "identical" if mse == 0.0 else f"{10 * math.log10(1.0 / mse):.1f}"
                    bright = img.sum() / max(ref.sum(), 1e-30)
                    print(f"| {label} | {medium} | {px:g} | {v} | {' / '.join(f'{c / 1e6:.2f}' for c in levels)} | {psnr} | {bright:.4f} |", flush=True)


def cmd_output(args):
    """The output stage's cost: pixel types, compressions, passes, deep files and the preview,
    interleaved with vdb_render's defaults; total time, the write stage (-v) and file size."""
    tmp = tempfile.mkdtemp(prefix="vdb_ewa_output_")
    label, path, cam = next(s for s in SCENES if s[0] == args.scene)
    common = ["-res", args.res, *cam.split()]
    out = os.path.join(tmp, "o.exr")
    variants = [
        ("default: half, zip (level 1)", []), ("half, zip --zip-level 4 (OpenEXR's default)", ["--zip-level", "4"]),
        ("float, zip (vdb_render's file type)", ["--exr-type", "float"]),
        ("float, zip --zip-level 4", ["--exr-type", "float", "--zip-level", "4"]),
        ("half, none", ["--compression", "none"]), ("half, zips", ["--compression", "zips"]),
        ("half, piz", ["--compression", "piz"]), ("half, dwaa", ["--compression", "dwaa"]),
        ("half, zip, --aov transmittance,shadow,emission", ["--aov", "transmittance,shadow,emission"]),
        ("half, zip, --preview", ["--preview", os.path.join(tmp, "p.png")]),
        ("--output-space lin_rec709", ["--output-space", "lin_rec709"]),
        ("--deep (half, zips)", ["--deep"]),
        ("--quality draft, half, zip", ["--quality", "draft"]),
        ("--quality draft, float, zip", ["--quality", "draft", "--exr-type", "float"]),
    ]
    configs = [("vdb_render defaults", ["vdb_render", path, os.path.join(tmp, "v.exr"), *common], None)]
    configs += [(name, [EWA, "render", path, out, *common, *extra, "-v"], out) for name, extra in variants]
    times = {name: [] for name, _, _ in configs}
    writes = {name: [] for name, _, _ in configs}
    sizes = {}
    for _ in range(args.repeat):
        for name, cmd, o in configs:
            dt, stdout = run(cmd)
            times[name].append(dt)
            if o:
                writes[name].append(float(re.search(r"write ([0-9.]+)", stdout).group(1)))
                sizes[name] = os.path.getsize(o) / 1e6
    base = statistics.median(times["vdb_render defaults"])
    print(f"# {label} {args.res}, --quality default unless noted: median of {args.repeat} interleaved rounds, {os.cpu_count()} cores")
    print("| output | total (s) | speed-up vs vdb_render defaults | write stage (s) | file (MB) |")
    print("|---|---|---|---|---|")
    for name, _, o in configs:
        t = statistics.median(times[name])
        w = f"{statistics.median(writes[name]):.3f}" if o else "-"
        size = f"{sizes[name]:.1f}" if o else f"{os.path.getsize(os.path.join(tmp, 'v.exr')) / 1e6:.1f}"
        print(f"| {name} | {t:.2f} | {base / t:.1f}x | {w} | {size} |", flush=True)


LEVEL_SETS = [
    ("cube_levelset", f"{ASSETS}/cube_levelset.vdb", "-translate 10,12,18 -lookat 0,0,0"),
    ("bunny_levelset", f"{ASSETS}/bunny_levelset.vdb", "-translate 0,0,4.859 -lookat 0,0,0"),
]


def cmd_surfaces(args):
    """Level sets: vdb_ewa's surface splats against vdb_render's ray tracer (same shader and
    camera), interleaved; medians, ratios and vdb_ewa's stage timings."""
    tmp = tempfile.mkdtemp(prefix="vdb_ewa_surfaces_")
    print(f"# level sets, {args.res}, -shader {args.shader}: median of {args.repeat} interleaved rounds, {os.cpu_count()} cores")
    print("| level set | vdb_render (s) | vdb_ewa (s) | speed-up | kernels (s) | rasterise (s) | write (s) |")
    print("|---|---|---|---|---|---|---|")
    for label, path, cam in LEVEL_SETS:
        common = ["-res", args.res, "-shader", args.shader, *cam.split()]
        vr, ours, stage = [], [], []
        for _ in range(args.repeat):
            vr.append(run(["vdb_render", path, os.path.join(tmp, "v.exr"), *common])[0])
            dt, out = run([EWA, "render", path, os.path.join(tmp, "o.exr"), *common, "-v"])
            ours.append(dt)
            stage.append(stages(out))
        a, b = statistics.median(vr), statistics.median(ours)
        st = stage[ours.index(b)] if b in ours else stage[0]
        print(f"| {label} | {a:.2f} | {b:.2f} | {a / b:.2f}x | {st.get('kernels', nan):.2f} | "
              f"{st.get('rasterise', nan):.2f} | {st.get('write', nan):.2f} |", flush=True)


def cmd_holes(args):
    """Issue 16: closed level sets against vdb_render's hit mask, every camera (bench/coverage.py)."""
    import coverage
    tmp = args.keep or tempfile.mkdtemp(prefix="vdb_ewa_holes_")
    os.makedirs(tmp, exist_ok=True)
    grids = coverage.write_generated(tmp)
    # (label, file, centre, size, default eye, where the close-up and grazing views look)
    sets = [("sphere", grids["sphere"], (0, 0, 0), 2.0, (1.2, 1.5, 3.8), (0, 0, 0)),
            ("torus", grids["torus"], (0, 0, 0), 2.7, (0.4, 2.5, 3.0), (1, 0, 0)),
            ("cube", f"{ASSETS}/cube_levelset.vdb", (0, 0, 0), 11.0, (10, 12, 18), (0, 0, 0)),
            ("bunny", f"{ASSETS}/bunny_levelset.vdb", (0, 0, 0), 2.0, (0, 0, 4.859), (0, 0, 0))]
    only = set(args.only.split(",")) if args.only else None
    sets = [s for s in sets if (not only or s[0] in only) and os.path.exists(s[1])]
    print(f"# level sets against vdb_render's hits (-shader matte), {args.res}, {os.cpu_count()} cores")
    print("| level set | camera | IoU | holes (2 px in) | holes (1 px in) | hit pixels | vdb_render (s) | vdb_ewa (s) | time ratio |")
    print("|---|---|---|---|---|---|---|---|---|")
    for label, path, centre, size, eye, focus in sets:
        for cam, camargs in coverage.cameras(path, centre, size, eye, focus).items():
            common = ["-res", args.res, "-shader", "matte", *camargs.split()]
            tag = f"{label}_{cam.split()[0]}"
            theirs, ours = os.path.join(tmp, tag + "_vr.exr"), os.path.join(tmp, tag + "_ewa.exr")
            t_vr = run(["vdb_render", path, theirs, *common])[0]
            t_ewa = run([*EWA_RENDER, path, ours, *common])[0]
            iou, h2, h1, hits = coverage.coverage(ours, theirs)
            print(f"| {label} | {cam} | {iou:.4f} | {h2} | {h1} | {hits} | {t_vr:.2f} | {t_ewa:.2f} | {t_ewa / t_vr:.2f} |",
                  flush=True)
    # The shaders against vdb_render's, at the default camera.
    print(f"\n# PSNR (dB) of vdb_ewa's RGB against vdb_render's, default camera, {args.res}")
    print("| level set | diffuse | matte | normal | position |")
    print("|---|---|---|---|---|")
    for label, path, centre, size, eye, focus in sets:
        cam = coverage.cameras(path, centre, size, eye, focus)["default"]
        row = []
        for shader in ("diffuse", "matte", "normal", "position"):
            common = ["-res", args.res, "-shader", shader, *cam.split()]
            theirs, ours = os.path.join(tmp, f"{label}_{shader}_vr.exr"), os.path.join(tmp, f"{label}_{shader}_ewa.exr")
            run(["vdb_render", path, theirs, *common])
            run([*EWA_RENDER, path, ours, *common])
            row.append(f"{diff(ours, theirs)[1]:.1f}")
        print(f"| {label} | {' | '.join(row)} |", flush=True)


ROOFLINE_SCENES = ["smoke", "pyro", "brain_mri", "cloud (grids/)"]


def roofline_binary(build):
    """bench/roofline's benchmark, configured and built in @a build if it is not there yet."""
    exe = os.path.join(build, "bench", "roofline", "vdb_ewa_roofline")
    if not os.path.exists(exe):
        subprocess.run(["cmake", "-S", ROOT, "-B", build, "-DCMAKE_BUILD_TYPE=Release", "-DVDB_EWA_BENCHMARKS=ON",
                        "-DVDB_EWA_BUILD_TESTS=OFF", "-DVDB_EWA_BUILD_CLI=OFF"], check=True, capture_output=True)
        subprocess.run(["cmake", "--build", build, "--target", "vdb_ewa_roofline"], check=True, capture_output=True)
    return exe


def cmd_roofline(args):
    """Issue 17: the rasteriser's achieved rate in real frames against this machine's peak for its
    inner loop (bench/roofline, one core, data in L1): the scalar backend (--simd off) against the
    scalar peak, the SIMD backend (--simd on, Highway) against the best vector peak measured
    (xsimd or Highway kernels)."""
    import json
    exe = roofline_binary(args.build)
    out = subprocess.run([exe, "--benchmark_format=json", "--benchmark_min_time=0.5"], check=True, capture_output=True, text=True).stdout
    peak = {b["name"]: b["items_per_second"] for b in json.loads(out)["benchmarks"]}
    kinds = ["scalar", "avx2"] + sorted({n.split("/")[1] for n in peak if "/hwy_" in n})
    print(f"# peak of the inner loop on one core (bench/roofline, data in L1), {os.cpu_count()} cores; "
          "avx2: xsimd, hwy_*: Highway (its dispatched target)")
    print("| kernel | " + " | ".join(f"{k} (M/s)" for k in kinds) + " |")
    print("|---|" + "---|" * len(kinds))
    for k in ("footprint_samples", "slab_composites"):
        print(f"| {k.replace('_', ' ')} | " + " | ".join(f"{peak.get(k + '/' + kind, nan) / 1e6:.0f}" for kind in kinds) + " |")
    best = {k: max(peak.get(f"{k}/{kind}", 0.0) for kind in kinds[1:]) for k in ("footprint_samples", "slab_composites")}
    print(f"\n# achieved in real frames, {args.res}, one thread (--threads 1), median of {args.repeat}; "
          "roofline time = samples / peak + composites / peak (vector peak: the best vector kernel above)")
    print("| scene | quality | footprint samples (M) | slab composites (M) | rasterise, scalar (s) | rasterise, SIMD (s) "
          "| SIMD speed-up | scalar / scalar roofline | SIMD / vector roofline |")
    print("|---|---|---|---|---|---|---|---|---|")
    tmp = tempfile.mkdtemp(prefix="vdb_ewa_roofline_")
    for label, path, cam in [s for s in SCENES if s[0] in ROOFLINE_SCENES]:
        if not os.path.exists(path):
            continue
        for quality in args.quality.split(","):
            t, samples, composites = {}, 0, 0
            for simd in ("off", "on"):
                times = []
                for _ in range(args.repeat):
                    _, stdout = run([EWA, "render", path, os.path.join(tmp, "o.exr"), "-res", args.res, *cam.split(),
                                     "--quality", quality, "--threads", "1", "--simd", simd, "-v"])
                    times.append(stages(stdout).get("rasterise", nan))
                    samples = int(re.search(r"([0-9]+) footprint samples", stdout).group(1))
                    composites = int(re.search(r"([0-9]+) slab composites", stdout).group(1))
                t[simd] = statistics.median(times)
            scalar = samples / peak["footprint_samples/scalar"] + composites / peak["slab_composites/scalar"]
            vector = samples / best["footprint_samples"] + composites / best["slab_composites"]
            print(f"| {label} | {quality} | {samples / 1e6:.1f} | {composites / 1e6:.1f} | {t['off']:.3f} | {t['on']:.3f} | "
                  f"{t['off'] / t['on']:.2f}x | {t['off'] / scalar:.1f} | {t['on'] / vector:.1f} |", flush=True)


CLOUD_VOXELS_AT_004 = 40049  # active voxels of `make-grid cloud --voxel-size 0.04`


def timed_peak(cmd):
    """(wall seconds, peak resident MB, stdout, exit code) of @a cmd, under /usr/bin/time."""
    t0 = time.perf_counter()
    p = subprocess.run(["/usr/bin/time", "-f", "%M", *cmd], capture_output=True, text=True)
    dt = time.perf_counter() - t0
    peak = float(p.stderr.strip().splitlines()[-1]) / 1024.0 * 1.048576  # KiB -> MB
    return dt, peak, p.stdout, p.returncode


def plot_scaling(rows, res, path):
    """The scaling table's plot (cmd_scaling, docs/figures/make_scaling.py): wall time and peak memory
    against active voxels."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.5))
    v = [r["voxels"] for r in rows]
    for key, colour, label in (("vdb_render", "tab:red", "vdb_render defaults"), ("default", "tab:blue", "vdb_ewa default"),
                               ("draft", "tab:green", "vdb_ewa draft")):
        ax1.plot(v, [r[key] for r in rows], "o-", color=colour, label=label)
    ax1.plot(v, [rows[0]["default"] * x / v[0] for x in v], ":", color="grey", label="linear in voxels")
    for key, colour, label in (("default_peak", "tab:blue", "vdb_ewa default"), ("draft_peak", "tab:green", "vdb_ewa draft")):
        ax2.plot(v, [r[key] for r in rows], "o-", color=colour, label=label)
    ax2.plot(v, [40e-6 * x for x in v], ":", color="grey", label="40 bytes per voxel (issue 37)")
    for ax, title in ((ax1, "wall time (s)"), (ax2, "peak memory (MB)")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("active voxels")
        ax.set_title(f"{title}, {res}")
        ax.grid(True, alpha=0.3)
        ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def cmd_scaling(args):
    """Issue 17: the same cloud (make-grid cloud) at voxel sizes giving 0.1M to 100M active voxels,
    rendered at one camera: time and peak memory of vdb_ewa --quality default and draft, and of
    vdb_render's defaults up to --peer-max million voxels (its time grows as voxels^(4/3): more
    voxels across every primary and shadow ray)."""
    tmp = args.keep or tempfile.mkdtemp(prefix="vdb_ewa_scaling_")
    os.makedirs(tmp, exist_ok=True)
    cam = "-translate 1.5,0.8,4.5 -lookat 0,0,0".split()
    print(f"# the sample cloud at {args.res}, one run each, {os.cpu_count()} cores; peak = resident set (getrusage / time -f %M)")
    print("| active voxels | voxel size | make-grid (s) | vdb_render (s) | vdb_render peak (MB) | default (s) | default peak (MB) "
          "| default B/voxel | speed-up | draft (s) | draft peak (MB) | draft B/voxel | speed-up |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    rows = []
    for millions in (float(m) for m in args.millions.split(",")):
        size = 0.04 * (CLOUD_VOXELS_AT_004 / (millions * 1e6)) ** (1.0 / 3.0)
        path = os.path.join(tmp, f"cloud_{millions:g}M.vdb")
        made = 0.0
        if not os.path.exists(path):
            made, _ = run([EWA, "make-grid", "cloud", path, "--voxel-size", f"{size:.6f}"])
        # -v prints the grid's count before rendering (an 8x8 frame may still exceed the budget).
        probe = subprocess.run([*EWA_RENDER, path, os.path.join(tmp, "o.exr"), "-res", "8x8", *cam, "-v"], capture_output=True, text=True)
        voxels = int(re.search(r"(\d+) active voxels", probe.stdout).group(1))
        row = {"voxels": voxels}
        cells = [f"{voxels / 1e6:.2f} M", f"{size:.4f}", f"{made:.1f}" if made else "(kept)"]
        if millions <= args.peer_max:
            dt, peak, _, code = timed_peak(["vdb_render", path, os.path.join(tmp, "theirs.exr"), "-res", args.res, *cam])
            row["vdb_render"] = dt if code == 0 else nan
            cells += [f"{dt:.2f}" if code == 0 else f"exit {code}", f"{peak:.0f}"]
        else:
            row["vdb_render"] = nan
            cells += ["not run", ""]
        for quality in ("default", "draft"):
            dt, peak, out, code = timed_peak([*EWA_RENDER, path, os.path.join(tmp, "ours.exr"), "-res", args.res, *cam, "--quality", quality, "-v"])
            row[quality], row[quality + "_peak"] = (dt, peak) if code == 0 else (nan, nan)
            speed = f"{row['vdb_render'] / dt:.1f}x" if code == 0 and row["vdb_render"] == row["vdb_render"] else ""
            cells += [f"{dt:.2f}" if code == 0 else f"exit {code}", f"{peak:.0f}", f"{peak * 1e6 / voxels:.0f}" if code == 0 else "", speed]
        rows.append(row)
        print("| " + " | ".join(cells) + " |", flush=True)
    if args.plot:
        try:
            import matplotlib  # noqa: F401 (plot_scaling draws with it)
        except ImportError:
            print("# no plot: apt-get install python3-matplotlib", file=sys.stderr)
            return
        plot_scaling(rows, args.res, args.plot)
        print(f"# wrote {args.plot}")


STABILITY_SCENES = ["smoke", "pyro", "pig", "brain_mri", "cloud (grids/)"]


def srgb8(path):
    """The RGB of an EXR as display values 0-255 (linear sRGB clipped to [0, 1], sRGB curve)."""
    import numpy as np
    import OpenImageIO as oiio
    img = oiio.ImageInput.open(path)
    px = img.read_image(0, 0, 0, 3, "float")
    img.close()
    v = np.clip(np.asarray(px, dtype=np.float64), 0.0, 1.0)
    return 255.0 * np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1.0 / 2.4) - 0.055)


def camera_path(camera, move, frame, frames):
    """vdb_render camera options of @a frame on an orbit (about the vertical through the look-at
    point, 1 degree a frame) or a dolly (away from the look-at point, the distance x 2.5 over the
    frames, geometrically) from the scene's camera."""
    import math
    words = camera.split()
    eye = [float(x) for x in words[words.index("-translate") + 1].split(",")]
    at = [float(x) for x in words[words.index("-lookat") + 1].split(",")]
    d = [e - a for e, a in zip(eye, at)]
    if move == "orbit":
        t = math.radians(frame)
        d = [d[0] * math.cos(t) + d[2] * math.sin(t), d[1], -d[0] * math.sin(t) + d[2] * math.cos(t)]
    else:
        k = 2.5 ** (frame / (frames - 1))
        d = [x * k for x in d]
    e = ",".join(f"{a + x:.6f}" for a, x in zip(at, d))
    return ["-translate", e, "-lookat", ",".join(f"{a:.6f}" for a in at)]


def cmd_stability(args):
    """Issue 17: temporal stability. Each scene along an orbit and a dolly, frame by frame, in
    --quality default and draft: the mean and the largest frame-to-frame change of the display
    values (0-255, sRGB, mean over pixels and RGB). Motion changes every frame; what the level
    of detail adds shows as draft's change over default's (the target: at most 1.5x), and as
    flicker: the mean second difference |I(t+1) - 2 I(t) + I(t-1)|, small for smooth motion and
    large where a frame jumps (popping) or a pattern finer than the motion aliases, and as jumps:
    the largest change over both its neighbours' changes, max(0, d(t) - max(d(t-1), d(t+1))),
    0 where the changes rise or fall smoothly (a dolly moves faster than flicker can tell). Frames
    already in --keep are reused."""
    import numpy as np
    tmp = args.keep or tempfile.mkdtemp(prefix="vdb_ewa_stability_")
    os.makedirs(tmp, exist_ok=True)
    qualities = args.quality.split(",")
    only = set(args.scenes.split(",")) if args.scenes != "all" else None
    print(f"# frame-to-frame change (0-255 display values), {args.frames} frames at {args.res}; orbit 1 degree a frame, "
          f"dolly 2.5x the distance over the frames")
    head = " | ".join(f"{q} mean | {q} max | {q} flicker | {q} jump" for q in qualities)
    print(f"| scene | move | {head} | {' | '.join(f'{q} / {qualities[0]}' for q in qualities[1:])} |")
    print("|---|---|" + "---|" * (4 * len(qualities) + len(qualities) - 1))
    # The sample cloud made finer: 1M voxels of about 0.1-0.3 pixels, where the level of detail merges most.
    generated = os.path.join(tmp, "cloud_1M.vdb")
    if (not only or "cloud1M" in only) and not os.path.exists(generated):
        run([EWA, "make-grid", "cloud", generated, "--voxel-size", f"{0.04 * (CLOUD_VOXELS_AT_004 / 1e6) ** (1.0 / 3.0):.6f}"])
    scenes = [s for s in SCENES if s[0] in STABILITY_SCENES] + [("cloud1M (generated)", generated, SCENES[5][2])]
    for label, path, camera in scenes:
        if (only and label.split()[0] not in only) or not os.path.exists(path):
            continue
        for move in ("orbit", "dolly"):
            cells, means = [], []
            for q in qualities:
                changes, flicker, frames = [], [], []
                for f in range(args.frames):
                    out = os.path.join(tmp, f"{label.split()[0]}_{move}_{q}_{f:03d}.exr")
                    if not (args.keep and os.path.exists(out)):
                        run([*EWA_RENDER, path, out, "-res", args.res, *camera_path(camera, move, f, args.frames),
                             "--quality", q, *args.extra.split()])
                    frames.append(srgb8(out))
                    if f >= 1:
                        changes.append(float(np.mean(np.abs(frames[-1] - frames[-2]))))
                    if f >= 2:
                        flicker.append(float(np.mean(np.abs(frames[-1] - 2.0 * frames[-2] + frames[-3]))))
                        frames.pop(0)
                means.append(statistics.mean(changes))
                jump = max(max(0.0, changes[t] - max(changes[t - 1], changes[t + 1])) for t in range(1, len(changes) - 1))
                cells += [f"{means[-1]:.2f}", f"{max(changes):.2f}", f"{statistics.mean(flicker):.3f}", f"{jump:.3f}"]
            ratios = [f"{m / means[0]:.2f}x" for m in means[1:]]
            print(f"| {label} | {move} | {' | '.join(cells)} | {' | '.join(ratios)} |", flush=True)


def plot(rows, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("# no plot: apt-get install python3-matplotlib", file=sys.stderr)
        return
    groups = sorted({(r["scene"], r["res"]) for r in rows})
    cols = min(4, len(groups))
    lines = (len(groups) + cols - 1) // cols
    fig, axes = plt.subplots(lines, cols, figsize=(6 * cols, 4.5 * lines), squeeze=False)
    for ax in axes.flat[len(groups):]:
        ax.set_visible(False)
    for ax, (scene, res) in zip(axes.flat, groups):
        for renderer, colour in (("vdb_render", "tab:red"), ("vdb_ewa", "tab:blue")):
            pts = [(r["time"], r["psnr_conv"], r["config"]) for r in rows
                   if r["scene"] == scene and r["res"] == res and r["renderer"] == renderer]
            pts.sort()
            front, best = [], -1e9
            for t, p, c in pts:
                if p > best:
                    front.append((t, p))
                    best = p
            ax.scatter([p[0] for p in pts], [p[1] for p in pts], color=colour, s=12, alpha=0.5)
            ax.plot([p[0] for p in front], [p[1] for p in front], color=colour, label=renderer)
            for t, p, c in pts:
                if c.startswith("quality") or c.endswith("defaults"):
                    ax.annotate(c.replace("quality ", ""), (t, p), fontsize=7)
        ax.set_xscale("log")
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel("PSNR vs vdb_render converged (dB)")
        ax.set_title(f"{scene} {res}")
        ax.legend()
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"# wrote {path}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    sp = sub.add_parser("speed")
    sp.add_argument("--res", default="1920x1080")
    sp.add_argument("--repeat", type=int, default=3)
    sg = sub.add_parser("sigma")
    sg.add_argument("--res", default="480x270")
    st = sub.add_parser("tradeoff")
    st.add_argument("--scenes", default="smoke,pyro,cloud")
    st.add_argument("--res", default="960x540")
    st.add_argument("--repeat", type=int, default=1)
    st.add_argument("--plot", default="")
    st.add_argument("--cache", default="", help="folder that keeps the reference images between runs")
    sx = sub.add_parser("targets")
    sx.add_argument("--scene", default="smoke")
    sx.add_argument("--res", default="1920x1080")
    sx.add_argument("--repeat", type=int, default=5)
    sx.add_argument("--cache", required=True, help="folder holding the tradeoff run's reference images")
    sy = sub.add_parser("python")
    sy.add_argument("--scene", default="smoke")
    sy.add_argument("--res", default="960x540")
    sy.add_argument("--repeat", type=int, default=7)
    sy.add_argument("--write", action="store_true", help="the Python process writes the EXR too, as the CLI does")
    def scene_parser(verb, repeat, res="960x540", scenes="pyro,smoke,cloud (grids/)"):
        """A verb of issue 55's figures: the scenes, the resolution, the quality, the rounds."""
        parser = sub.add_parser(verb)
        parser.add_argument("--scenes", default=scenes)
        parser.add_argument("--res", default=res)
        parser.add_argument("--quality", default="default")
        parser.add_argument("--repeat", type=int, default=repeat)
        return parser
    scene_parser("scene", 5)
    scene_parser("turntable", 3).add_argument("--frames", type=int, default=24)
    scene_parser("progressive", 7, res="480x270", scenes="pyro")
    scene_parser("soak", 1, scenes="pyro,smoke").add_argument("--moves", type=int, default=100)
    sis = sub.add_parser("imagelod-scale")
    sis.add_argument("--res", default="480x270")
    sis.add_argument("--px", default="0.1,3,20")
    sis.add_argument("--values", default="4,2,1")
    sd = sub.add_parser("draft")
    sd.add_argument("--res", default="1920x1080")
    sd.add_argument("--repeat", type=int, default=3)
    sc = sub.add_parser("cull")
    sc.add_argument("--res", default="1920x1080")
    sc.add_argument("--repeat", type=int, default=3)
    sbl = sub.add_parser("blur")
    sbl.add_argument("--res", default="480x270")
    sbl.add_argument("--repeat", type=int, default=3)
    sbl.add_argument("--ref-samples", type=int, default=64)
    sbl.add_argument("--ref-step", type=float, default=0.25)
    sbl.add_argument("--fstop", type=float, default=0.05)
    sbl.add_argument("--keep", default="", help="folder that keeps the grids and references between runs")
    sl = sub.add_parser("lights")
    sl.add_argument("--res", default="480x270")
    sl.add_argument("--repeat", type=int, default=3)
    sl.add_argument("--ref-step", type=float, default=0.25)
    sl.add_argument("--keep", default="", help="folder that keeps the references between runs")
    svo = sub.add_parser("volumes")
    svo.add_argument("--res", default="480x270")
    svo.add_argument("--repeat", type=int, default=3)
    svo.add_argument("--ref-step", type=float, default=0.25)
    svo.add_argument("--keep", default="", help="folder that keeps the moved cloud and the reference between runs")
    si = sub.add_parser("imagelod")
    si.add_argument("--res", default="1920x1080")
    si.add_argument("--values", default="4,2,4c,2c,1c")
    si.add_argument("--repeat", type=int, default=3)
    so = sub.add_parser("output")
    so.add_argument("--scene", default="smoke")
    so.add_argument("--res", default="1920x1080")
    so.add_argument("--repeat", type=int, default=3)
    sv = sub.add_parser("surfaces")
    sv.add_argument("--res", default="1920x1080")
    sv.add_argument("--shader", default="diffuse")
    sv.add_argument("--repeat", type=int, default=3)
    sh = sub.add_parser("holes")
    sh.add_argument("--res", default="640x480")
    sh.add_argument("--only", default="", help="comma-separated: sphere,torus,cube,bunny")
    sh.add_argument("--keep", default="", help="folder that keeps the grids and images")
    sl = sub.add_parser("ladder")
    sl.add_argument("--scenes", default="all")
    sl.add_argument("--res", default="960x540")
    sl.add_argument("--repeat", type=int, default=1)
    sl.add_argument("--cache", default="", help="folder that keeps vdb_render's converged images between runs")
    sl.add_argument("--plot", default="")
    sr = sub.add_parser("roofline")
    sr.add_argument("--res", default="1920x1080")
    sr.add_argument("--quality", default="draft,default")
    sr.add_argument("--repeat", type=int, default=3)
    sr.add_argument("--build", default=os.path.join(ROOT, "build-bench"), help="where bench/roofline is built")
    sc = sub.add_parser("scaling")
    sc.add_argument("--res", default="1920x1080")
    sc.add_argument("--millions", default="0.1,0.3,1,3,10,30,100")
    sc.add_argument("--peer-max", type=float, default=3.0, help="largest cloud (million voxels) vdb_render renders")
    sc.add_argument("--keep", default="", help="folder that keeps the generated clouds between runs")
    sc.add_argument("--plot", default="", help="write the scaling plot (PNG) here")
    sb = sub.add_parser("stability")
    sb.add_argument("--res", default="480x270")
    sb.add_argument("--frames", type=int, default=24)
    sb.add_argument("--quality", default="default,draft")
    sb.add_argument("--scenes", default="all", help="comma-separated: smoke,pyro,pig,brain_mri,cloud,cloud1M")
    sb.add_argument("--extra", default="", help="more vdb_ewa options for every frame")
    sb.add_argument("--keep", default="", help="folder that keeps the frames")
    ssc = sub.add_parser("scale")
    ssc.add_argument("--res", default="240x135")
    ssc.add_argument("--px", default="0.1,0.3,1,3", help="pixels a voxel spans")
    ssc.add_argument("--media", default="all", help="thin (vdb_render's model), thick (physical shadows) or all")
    ssc.add_argument("--scenes", default="all", help="comma-separated: cloud,smoke,pyro,pig")
    ssc.add_argument("--repeat", type=int, default=3)
    sub.add_parser("tiles")
    sa = sub.add_parser("analytic")
    sa.add_argument("--res", default="320x180")
    sp2 = sub.add_parser("plot")
    sp2.add_argument("table", help="saved output of a tradeoff run")
    sp2.add_argument("--plot", required=True)
    sp2.add_argument("--res", default="960x540", help="the resolution of a ladder table")
    a = ap.parse_args()
    {"speed": cmd_speed, "sigma": cmd_sigma, "tradeoff": cmd_tradeoff, "targets": cmd_targets,
     "output": cmd_output, "imagelod": cmd_imagelod, "draft": cmd_draft, "imagelod-scale": cmd_imagelod_scale, "surfaces": cmd_surfaces, "holes": cmd_holes, "plot": cmd_plot, "ladder": cmd_ladder,
     "analytic": cmd_analytic, "roofline": cmd_roofline, "scaling": cmd_scaling,
     "stability": cmd_stability, "python": cmd_python, "scene": cmd_scene, "turntable": cmd_turntable, "progressive": cmd_progressive, "soak": cmd_soak, "cull": cmd_cull, "blur": cmd_blur, "lights": cmd_lights, "volumes": cmd_volumes, "scale": cmd_scale, "tiles": cmd_tiles}[a.cmd](a)


if __name__ == "__main__":
    main()
