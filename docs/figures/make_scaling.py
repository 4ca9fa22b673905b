#!/usr/bin/python3
"""docs/scaling.png (docs/performance.md, scaling): wall time and peak memory at 1920x1080
against active voxels, the sample cloud (`vdb_ewa make-grid cloud`) made finer from 0.1M to 100M
voxels, vdb_ewa default and draft and vdb_render's defaults (up to 3M voxels): the plot of
`bench/bench.py scaling`.

Two ways:
- default: redraw the plot from the saved table, bench/results/scaling_1920x1080.txt (or
  --table FILE), in seconds, with the plotting code of bench.py scaling (bench.plot_scaling; kept in step with it
  here). The committed image's memory panel labels its dotted line "80 bytes per voxel": it was
  drawn before bench.py's line became 40 bytes per voxel (issue 37), so a redraw differs there.
- --measure: run bench.py scaling again (the grids up to 100M voxels take several GB of disk
  and memory and the whole run tens of minutes on two cores; --keep DIR keeps the grids). Run
  it on a quiet machine. The table goes beside the plot (DIR/scaling_1920x1080.txt).

Needs /usr/bin/python3 with matplotlib (python3-matplotlib; scripts/install-deps.sh --bench);
--measure also vdb_ewa ($VDB_EWA_BIN, default vdb_ewa on PATH) and vdb_render.

Usage: docs/figures/make_scaling.py [--out DIR] [--table FILE | --measure [--keep DIR]]
  writes DIR/scaling.png (default DIR: a new temporary folder; --out docs replaces the
  committed image)."""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RES = "1920x1080"


def rows_of(table):
    """The rows of a bench.py scaling table: voxels, vdb_render, default, draft (s) and peaks (MB)."""
    nan = float("nan")
    number = lambda cell: float(cell) if re.fullmatch(r"[0-9.]+", cell) else nan
    rows = []
    for line in open(table):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if not line.startswith("| ") or len(cells) != 13 or not cells[0].endswith(" M"):
            continue
        rows.append(dict(voxels=float(cells[0][:-2]) * 1e6, vdb_render=number(cells[3]), default=number(cells[5]),
                         default_peak=number(cells[6]), draft=number(cells[9]), draft_peak=number(cells[10])))
    if not rows:
        sys.exit(f"{table}: no rows of a bench.py scaling table")
    return rows


def plot(rows, path):
    """bench.py cmd_scaling's plot (bench.plot_scaling)."""
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "bench"))
    import bench
    bench.plot_scaling(rows, RES, path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="", help="the folder for scaling.png (default: a new temporary folder)")
    parser.add_argument("--table", default=os.path.join(ROOT, "bench", "results", "scaling_1920x1080.txt"))
    parser.add_argument("--measure", action="store_true", help="run bench.py scaling (long) instead of redrawing")
    parser.add_argument("--keep", default="", help="with --measure: the folder that keeps the generated grids")
    args = parser.parse_args()
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        sys.exit(f"{sys.argv[0]}: no matplotlib (apt-get install python3-matplotlib)")
    out = os.path.abspath(args.out or tempfile.mkdtemp(prefix="vdb_ewa_figure_"))
    os.makedirs(out, exist_ok=True)
    target = os.path.join(out, "scaling.png")
    if args.measure:
        ewa = os.environ.get("VDB_EWA_BIN", os.environ.get("VDB_EWA", "vdb_ewa"))
        for tool in (ewa, "vdb_render"):
            if shutil.which(tool) is None:
                sys.exit(f"{sys.argv[0]}: {tool} not found (set VDB_EWA_BIN)")
        env = dict(os.environ, VDB_EWA_BIN=os.path.abspath(ewa) if os.sep in ewa else shutil.which(ewa))
        command = [sys.executable, os.path.join(ROOT, "bench", "bench.py"), "scaling", "--res", RES, "--plot", target]
        if args.keep:
            command += ["--keep", os.path.abspath(args.keep)]
        with open(os.path.join(out, "scaling_1920x1080.txt"), "w") as table:
            subprocess.run(command, check=True, env=env, stdout=table)
    else:
        plot(rows_of(args.table), target)
    print(target)


if __name__ == "__main__":
    main()
