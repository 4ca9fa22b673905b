#!/usr/bin/env bash
# docs/pareto.png (docs/performance.md): time against PSNR to vdb_render's converged image at
# 960x540, vdb_ewa's presets against vdb_render's settings, one panel a scene: the plot of
# `bench/bench.py ladder`.
#
# Two ways:
# - default: redraw the plot from a saved ladder table (bench/bench.py plot), in seconds. The
#   committed image was drawn from the table of commit d8ed330:
#     git show d8ed330:bench/results/ladder_960x540.txt > /tmp/ladder.txt
#     docs/figures/make_pareto.sh --table /tmp/ladder.txt
# - --measure: run the ladder again (bench/bench.py ladder --scenes all --res 960x540), which
#   renders vdb_render's converged image of every scene first (tens of minutes on two cores;
#   --cache DIR keeps them for the next run) and times every setting. Run it on a quiet
#   machine. The table goes beside the plot (DIR/ladder_960x540.txt); copy it to bench/results/
#   with the plot (CONTRIBUTING.md).
#
# Needs /usr/bin/python3 with matplotlib (python3-matplotlib; scripts/install-deps.sh --bench);
# --measure also vdb_ewa ($VDB_EWA_BIN, default vdb_ewa on PATH), vdb_render, oiiotool and the
# shared assets ($VDB_EWA_ASSETS, default ../shared/grids).
#
# Usage: docs/figures/make_pareto.sh [--out DIR] [--table FILE | --measure [--cache DIR]]
#   writes DIR/pareto.png (default DIR: a new temporary folder; --out docs replaces the
#   committed image).
set -euo pipefail
source "$(dirname "$0")/figure_common.sh"
out="" table="" measure="" cache=""
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    --table) table="$2"; shift 2 ;;
    --measure) measure=1; shift ;;
    --cache) cache="$2"; shift 2 ;;
    *) echo "usage: $0 [--out DIR] [--table FILE | --measure [--cache DIR]]" >&2; exit 2 ;;
  esac
done
out="$(out_dir "$out")"
[ -n "$table" ] && table="$(path_of "$table")"
[ -n "$cache" ] && cache="$(path_of "$cache")"
bench_env
cd "$(dirname "$0")/../.."
python="${PYTHON:-/usr/bin/python3}"
need_matplotlib "$python"
mkdir -p "$out"
if [ -n "$measure" ]; then
  need_tools "$VDB_EWA_BIN" vdb_render oiiotool
  "$python" bench/bench.py ladder --scenes all --res 960x540 ${cache:+--cache "$cache"} \
    --plot "$out/pareto.png" | tee "$out/ladder_960x540.txt"
else
  "$python" bench/bench.py plot "${table:-bench/results/ladder_960x540.txt}" --res 960x540 --plot "$out/pareto.png"
fi
echo "$out/pareto.png"
