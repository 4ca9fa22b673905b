#!/usr/bin/env bash
# docs/pareto_1080.png (docs/performance.md, the trade-off at 1920x1080): time against PSNR to
# vdb_render's converged image for every asset, presets and knob sweeps (dots) with each
# renderer's Pareto front: the plot of `bench/bench.py tradeoff`.
#
# Two ways:
# - default: redraw the plot (bench/bench.py plot) from the two saved tables it was drawn from,
#   bench/results/tradeoff_assets_1920x1080.txt and tradeoff_smoke_1920x1080.txt (smoke from
#   its own run), in seconds. This gives the committed image pixel for pixel.
# - --measure: run the trade-off again (bench/bench.py tradeoff --res 1920x1080 on every asset;
#   vdb_render's converged images at 1920x1080 take about 10 minutes each on two cores, so hours
#   in all: --cache DIR keeps the references). Run it on a quiet machine. The table goes beside
#   the plot (DIR/tradeoff_1920x1080.txt).
#
# Needs /usr/bin/python3 with matplotlib (python3-matplotlib; scripts/install-deps.sh --bench);
# --measure also vdb_ewa ($VDB_EWA_BIN, default vdb_ewa on PATH), vdb_render, oiiotool and the
# shared assets ($VDB_EWA_ASSETS, default ../shared/grids).
#
# Usage: docs/figures/make_pareto_1080.sh [--out DIR] [--measure [--cache DIR]]
#   writes DIR/pareto_1080.png (default DIR: a new temporary folder; --out docs replaces the
#   committed image).
set -euo pipefail
source "$(dirname "$0")/figure_common.sh"
out="" measure="" cache=""
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    --measure) measure=1; shift ;;
    --cache) cache="$2"; shift 2 ;;
    *) echo "usage: $0 [--out DIR] [--measure [--cache DIR]]" >&2; exit 2 ;;
  esac
done
out="$(out_dir "$out")"
[ -n "$cache" ] && cache="$(path_of "$cache")"
bench_env
cd "$(dirname "$0")/../.."
python="${PYTHON:-/usr/bin/python3}"
need_matplotlib "$python"
mkdir -p "$out"
if [ -n "$measure" ]; then
  need_tools "$VDB_EWA_BIN" vdb_render oiiotool
  "$python" bench/bench.py tradeoff --scenes smoke,pyro,pig,fog_tommy_v5,brain_mri,cloud,tiles,smoke_double --res 1920x1080 \
    ${cache:+--cache "$cache"} --plot "$out/pareto_1080.png" | tee "$out/tradeoff_1920x1080.txt"
else
  tmp="$(mktemp -d)"
  trap 'rm -rf "$tmp"' EXIT
  cat bench/results/tradeoff_assets_1920x1080.txt bench/results/tradeoff_smoke_1920x1080.txt >"$tmp/tradeoff.txt"
  "$python" bench/bench.py plot "$tmp/tradeoff.txt" --plot "$out/pareto_1080.png"
fi
echo "$out/pareto_1080.png"
