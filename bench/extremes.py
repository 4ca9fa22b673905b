#!/usr/bin/python3
"""vdb_ewa at the numerical extremes: every numeric option of `vdb_ewa render` at the ends of the
range its --help documents, and at 0, -1, the denormals 5e-324 and 1e-310, the largest float and
double, inf and nan (vectors: the value in every component), on three assets at 160x90.

  bench/extremes.py [--quick] [--vdb-ewa PATH] [--out FILE]

Per run: exit code, wall time (and its ratio to the asset's default command line, median of 3),
peak memory (ru_maxrss of the child, from os.wait4) and stderr's first line. One run at a time,
each in its own process group with a hard timeout of max(60 s, 20 x default) and RLIMIT_AS 8 GB.
A run is a FINDING when it crashed, timed out, took over 10x the default, peaked above 1 GB on the
cloud (4 GB on the others; --res: time per pixel against the default's, and 64 bytes a pixel more), exited with a code outside {0,2,3,4,5}, failed with more than one
stderr line or one over 300 characters (docs/numerics.md, docs/reliability.md), or exited 0
without writing its image. --quick: the cloud only. Writes bench/results/extremes_160x90.txt
(extremes_160x90_quick.txt with --quick). Needs the shared assets ($VDB_EWA_ASSETS, default
../shared/grids); a missing asset is skipped. Run with /usr/bin/python3 (stdlib only).
"""
import argparse
import os
import re
import resource
import shlex
import shutil
import signal
import statistics
import subprocess
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.path.normpath(os.environ.get("VDB_EWA_ASSETS", os.path.join(ROOT, "..", "shared", "grids")))
RES = "160x90"
MEMORY_CAP = 8 << 30  # RLIMIT_AS of every run
OK_EXITS = {0, 2, 3, 4, 5}  # docs/farm.md: success, bad options, input, output, memory budget

# (label, file, camera, its grid's name for the contexts below, peak MB above which a run is a finding)
ASSETS = [
    ("cloud", f"{ROOT}/grids/cloud.vdb", ["--translate", "1.5,0.8,4.5"], "density", 1024),
    ("pyro", f"{SHARED}/pyro.vdb", ["--translate", "0.225,2.175,15.75", "--lookat", "0.225,2.175,-0.225"],
     "density", 4096),
    ("bunny", f"{SHARED}/bunny_levelset.vdb", ["--translate", "0,0,4.859", "--lookat", "0,0,0"], "surface", 4096),
]

# Every option gets these; the ends of its documented range are added from the tables below.
EXTREMES = ["0", "-1", "5e-324", "1e-310", "3.4028234663852886e38", "1.7976931348623157e308", "inf", "nan"]
INT_EXTREMES = ["2147483647", "2147483648"]  # INT options also: the largest int and one past it

# FLOAT and INT options of `render --help` -> the ends of the range its text gives (none: no range).
SCALARS = {
    "--fov": ("0", "180"),              # (0, 180) degrees
    "--focal": (), "--aperture": (), "--frame": (), "--near": (), "--far": (),
    "--environment-lights": ("1", "64"),  # INT
    "--environment-intensity": ("0",),  # >= 0
    "--gain": (), "--cutoff": (),
    "--shadowstep": ("0.001",),         # >= 0.001
    "--shadow-res": ("0.25", "16"),
    "--step": (),
    "--kernel-sigma": ("0.1", "4"), "--surface-sigma": ("0.1", "4"),
    "--lowpass": (), "--cutoff-radius": (), "--slab": (),
    "--tile-spacing": ("1",),           # INT, "1 to voxelise"
    "--refine": ("1", "4"), "--refine-emission": ("1", "4"),  # INT
    "--lod": ("0", "64"), "--lod-error": ("0", "1"),
    "--iso": (), "--iso-opacity": ("0", "1"), "--isovalue": (),
    "--emission-intensity": ("0", "1e6"),
    "--temperature-scale": (), "--temperature-offset": ("-1e6", "1e6"),  # "within 1e6"
    "--blackbody-intensity": ("0", "1e6"),
    "--samples": (),                    # INT
    "--max-memory": ("64M", "1e18"),    # TEXT, bytes
}
INTS = {"--environment-lights", "--tile-spacing", "--refine", "--refine-emission", "--samples"}
# Comma-separated TEXT options -> (components, range ends of each); the value goes in every component.
VECTORS = {
    "--translate": (3, ()), "--rotate": (3, ()), "--lookat": (3, ()), "--up": (3, ()),
    "--absorb": (3, ("0", "1e6")), "--scatter": (3, ("0", "1e6")), "--emission": (3, ("0", "1e6")),
    "--ambient": (3, ("0", "1e6")), "--emission-color": (3, ("0", "1e6")),
}
# --light: the direction X,Y,Z (default colour), then the colour R,G,B after the default direction.
LIGHT_DIRECTION, LIGHT_COLOUR = "{v},{v},{v}", "0.3,0.3,0,{v},{v},{v}"
RES_VALUES = ["1x1", "65536x1", "1x65536", "16384x8192", "65536x65536", "0x0"]  # 16384x8192: the 2^27 cap
THREADS = ["0", "1", "1024", "1025", "-1", "2147483647"]  # range [0, 1024]
# Camera options a swept option replaces (--rotate and --lookat aim the camera each).
REPLACES = {"--translate": ["--translate"], "--lookat": ["--lookat"], "--rotate": ["--lookat"]}
# Not about the frame: sequences and farm tasks.
EXCLUDED = {"--frames", "--chunk", "--task", "--skip-newer-than"}

# Options that matter only with others: a run of the option gets these too ({grid}: the asset's grid,
# {env}: a 4x2 latitude-longitude image of constant radiance 1 the script writes). Where the context
# fails on an asset by itself (emission grids on a level set), the option is swept without it.
CONTEXT = {
    "--frame": ["--camera", "ortho"],
    "--step": ["--method", "raymarch"],
    "--iso-opacity": ["--iso", "0.5"],
    "--environment-lights": ["--environment", "{env}"],
    "--environment-intensity": ["--environment", "{env}"],
    "--emission-intensity": ["--emission-grid", "{grid}"],
    "--emission-color": ["--emission-grid", "{grid}"],
    "--refine-emission": ["--emission-grid", "{grid}"],
    "--temperature-scale": ["--temperature", "{grid}", "--temperature-offset", "1500"],
    "--temperature-offset": ["--temperature", "{grid}", "--temperature-scale", "5000"],
    "--blackbody-intensity": ["--temperature", "{grid}", "--temperature-scale", "5000"],
}


def pixels_of(res):
    """Pixels of a WxH value (0 where it is not one)."""
    m = re.fullmatch(r"(\d+)x(\d+)", res)
    return int(m[1]) * int(m[2]) if m else 0


def sweep():
    """(option as shown, value as shown, arguments) of every run, in order."""
    runs = [("--res", v, ["--res", v]) for v in RES_VALUES]
    runs += [("--threads", v, ["--threads", v]) for v in THREADS]
    for opt, ends in SCALARS.items():
        values = list(ends) + EXTREMES + (INT_EXTREMES if opt in INTS else [])
        runs += [(opt, v, [opt, v]) for v in values]
    for opt, (n, ends) in VECTORS.items():
        runs += [(opt, v, [opt, ",".join([v] * n)]) for v in list(ends) + EXTREMES]
    runs += [("--light X,Y,Z", v, ["--light", LIGHT_DIRECTION.format(v=v)]) for v in EXTREMES]
    runs += [("--light R,G,B", v, ["--light", LIGHT_COLOUR.format(v=v)]) for v in ["0", "1e6"] + EXTREMES]
    return runs


def check_help(ewa):
    """Warn about FLOAT and INT options of --help the tables above do not sweep (a new option)."""
    text = subprocess.run([ewa, "render", "--help"], capture_output=True, text=True).stdout
    found = re.findall(r"^\s+(?:-\w,)?(--[\w-]+)(?:,--[\w-]+)? (?:FLOAT|INT)\b", text, re.M)
    known = set(SCALARS) | set(VECTORS) | EXCLUDED | {"--threads", "--res", "--light"}
    return [f"warning: {o} is a numeric option of --help that this script does not sweep"
            for o in found if o not in known]


def write_environment(path, w=4, h=2):
    """A Radiance .hdr of constant radiance 1 (uncompressed RGBE: rows under 8 pixels are never RLE)."""
    with open(path, "wb") as f:
        f.write(f"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n".encode())
        f.write(bytes([128, 128, 128, 129]) * (w * h))


def cap_memory():
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_CAP, MEMORY_CAP))


def run(cmd, timeout):
    """(exit code or None on timeout, seconds, peak MB, stderr lines) of one run in its own group."""
    with tempfile.TemporaryFile() as err:
        fired = threading.Event()

        def kill(pid):
            fired.set()
            try:
                os.killpg(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        t0 = time.perf_counter()
        p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err, stdin=subprocess.DEVNULL,
                             start_new_session=True, preexec_fn=cap_memory)
        timer = threading.Timer(timeout, kill, [p.pid])
        timer.start()
        _, status, usage = os.wait4(p.pid, 0)
        dt = time.perf_counter() - t0
        timer.cancel()
        p.returncode = code = os.waitstatus_to_exitcode(status)
        err.seek(0)
        lines = err.read().decode(errors="replace").splitlines()
    timed_out = fired.is_set() and code == -signal.SIGKILL
    return (None if timed_out else code), dt, usage.ru_maxrss / 1024, lines


def clean(folder, keep):
    for f in os.listdir(folder):
        if f != keep:
            os.remove(os.path.join(folder, f))


def findings_of(code, secs, ratio, peak, lines, wrote, peak_limit):
    why = []
    if code is None:
        why.append("timeout")
    elif code < 0:
        why.append(f"crashed (signal {-code}, {signal.Signals(-code).name})")
    elif code not in OK_EXITS:
        why.append(f"exit code {code} not in {{0,2,3,4,5}}")
    if code is not None and ratio > 10:
        why.append(f"{ratio:.1f}x the default time")
    if peak > peak_limit:
        why.append(f"peak {peak:.0f} MB > {peak_limit} MB")
    if code not in (0, None):
        if len(lines) > 1:
            why.append(f"{len(lines)} stderr lines on failure")
        if lines and len(lines[0]) > 300:
            why.append(f"stderr line of {len(lines[0])} characters")
    if code == 0 and not wrote:
        why.append("exit 0 without the output file")
    return why


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="the cloud only")
    default_bin = os.path.join(ROOT, "build", "cmd", "vdb_ewa", "vdb_ewa")
    if not os.path.exists(default_bin):
        default_bin = os.path.join(ROOT, "build-tests", "cmd", "vdb_ewa", "vdb_ewa")
    ap.add_argument("--vdb-ewa", default=os.environ.get("VDB_EWA_BIN", default_bin))
    ap.add_argument("--out", help="report file (default bench/results/extremes_160x90[_quick].txt)")
    args = ap.parse_args()
    out = args.out or os.path.join(ROOT, "bench", "results", f"extremes_{RES}{'_quick' if args.quick else ''}.txt")

    report = []

    def say(line=""):
        print(line, flush=True)
        report.append(line)

    tmp = tempfile.mkdtemp(prefix="vdb_ewa_extremes_")
    env = os.path.join(tmp, "env.hdr")
    write_environment(env)
    image = os.path.join(tmp, "out.exr")
    runs = sweep()
    version = subprocess.run([args.vdb_ewa, "--version"], capture_output=True, text=True).stdout.strip()
    say(f"# vdb_ewa render at the numerical extremes, {RES}, {args.vdb_ewa} ({version}), {os.cpu_count()} cores, "
        f"RLIMIT_AS {MEMORY_CAP >> 30} GB, {time.strftime('%Y-%m-%d %H:%M')}")
    for w in check_help(args.vdb_ewa):
        say(w)
    say("# {env} is a 4x2 Radiance image of constant radiance 1; ratio: time / the default's "
        "(the asset's command line, with the option's context)")
    rows, findings, summary = [], [], []
    for label, path, camera, grid, peak_limit in ASSETS[:1] if args.quick else ASSETS:
        if not os.path.exists(path):
            say(f"\n## {label}: {path} missing, skipped")
            continue
        base = [args.vdb_ewa, "render", path, image, "--res", RES, *camera]
        subst = {"{grid}": grid, "{env}": env}

        def context_of(opt):
            return [subst.get(a, a) for a in CONTEXT.get(opt, [])]

        # The default time of each context, median of 3; a context that fails by itself is dropped.
        defaults = {}
        for ctx in sorted({tuple(context_of(o)) for o in CONTEXT} | {()}):
            times, code, lines = [], 0, []
            for _ in range(3):
                code, dt, _, lines = run(base + list(ctx), 600)
                clean(tmp, "env.hdr")
                times.append(dt)
            defaults[ctx] = statistics.median(times) if code == 0 else None
            note = f"{defaults[ctx]:.3f} s" if code == 0 else f"fails (exit {code}: {lines[0] if lines else ''}), dropped"
            say(f"# {label} default{' + ' + shlex.join(ctx) if ctx else ''}: {note}")
        say(f"\n## {label}: {path}, {shlex.join(camera)}\n")
        say("| option | value | asset | exit | s | x default | peak MB | stderr's first line (its length) |")
        say("|---|---|---|---|---|---|---|---|")
        worst_ratio, worst_peak = (0, ""), (0, "")
        for opt, value, extra in runs:
            ctx = tuple(context_of(opt.split()[0]))
            if defaults.get(ctx) is None:
                ctx = ()
            default = defaults[ctx]
            cam = list(camera)
            for o in REPLACES.get(opt, []):
                if o in cam:
                    i = cam.index(o)
                    del cam[i:i + 2]
            cmd = [args.vdb_ewa, "render", path, image] + ([] if opt == "--res" else ["--res", RES]) + cam + list(ctx) + extra
            # An image's time and memory grow with its pixels: --res is held to the default's time
            # per pixel and to 64 bytes a pixel beyond the limit (the frame, the EXR's buffer and a
            # level set's surface layers).
            pixels = pixels_of(value) if opt == "--res" else 0
            scale = max(1.0, pixels / pixels_of(RES))
            code, secs, peak, lines = run(cmd, min(900.0, max(60.0, 20 * default * scale)))
            wrote = os.path.exists(image)
            clean(tmp, "env.hdr")
            ratio = secs / (default * scale)
            first = lines[0] if lines else ""
            shown = "timeout" if code is None else (f"SIG{signal.Signals(-code).name[3:]}" if code < 0 else str(code))
            say(f"| {opt} | {value} | {label} | {shown} | {secs:.2f} | {ratio:.1f} | {peak:.0f} | "
                f"{first[:100].replace('|', '/')}{' (' + str(len(first)) + ')' if first else ''} |")
            worst_ratio = max(worst_ratio, (ratio, f"{opt} {value}{', timeout' if code is None else ''}"))
            worst_peak = max(worst_peak, (peak, f"{opt} {value}"))
            why = findings_of(code, secs, ratio, peak, lines, wrote, peak_limit + 64 * pixels / 2**20)
            if why:
                repro = shlex.join(cmd).replace(tmp + "/", "$TMP/")
                findings.append(f"- {label}, {opt} {value}: {'; '.join(why)} ({shown}, {secs:.1f} s, "
                                f"{peak:.0f} MB){': ' + first[:300] if first else ''}\n    {repro}")
            rows.append(label)
        summary.append(f"- {label}: {rows.count(label)} runs; worst time {worst_ratio[0]:.1f}x the default "
                       f"({worst_ratio[1]}); worst peak {worst_peak[0]:.0f} MB ({worst_peak[1]})")
    say(f"\n## Summary: {len(rows)} runs\n")
    for s in summary:
        say(s)
    say(f"\n## FINDINGS ({len(findings)}; $TMP holds out.exr and env.hdr)\n")
    for f in findings or ["none"]:
        say(f)
    shutil.rmtree(tmp)
    os.makedirs(os.path.dirname(out), exist_ok=True)
    with open(out, "w") as f:
        f.write("\n".join(report) + "\n")


if __name__ == "__main__":
    main()
