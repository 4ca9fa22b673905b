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
absolute() { case "$1" in /*) echo "$1" ;; */*) echo "$PWD/$1" ;; *) echo "$1" ;; esac; } # a bare name: PATH
path_of() { case "$1" in /*) echo "$1" ;; *) echo "$PWD/$1" ;; esac; }
out="$(path_of "${out:-$(mktemp -d)}")"
[ -n "$table" ] && table="$(path_of "$table")"
[ -n "$cache" ] && cache="$(path_of "$cache")"
VDB_EWA_BIN="$(absolute "${VDB_EWA_BIN:-${VDB_EWA:-vdb_ewa}}")"
[ -n "${VDB_EWA_ASSETS:-}" ] && export VDB_EWA_ASSETS="$(path_of "$VDB_EWA_ASSETS")"
export VDB_EWA_BIN
cd "$(dirname "$0")/../.."
python="${PYTHON:-/usr/bin/python3}"
"$python" -c "import matplotlib" 2>/dev/null ||
  { echo "$0: $python has no matplotlib (apt-get install python3-matplotlib)" >&2; exit 1; }
mkdir -p "$out"
if [ -n "$measure" ]; then
  for tool in "$VDB_EWA_BIN" vdb_render oiiotool; do
    command -v "$tool" >/dev/null || { echo "$0: $tool not found" >&2; exit 1; }
  done
  "$python" bench/bench.py ladder --scenes all --res 960x540 ${cache:+--cache "$cache"} \
    --plot "$out/pareto.png" | tee "$out/ladder_960x540.txt"
else
  "$python" bench/bench.py plot "${table:-bench/results/ladder_960x540.txt}" --res 960x540 --plot "$out/pareto.png"
fi
echo "$out/pareto.png"
