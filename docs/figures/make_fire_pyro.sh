#!/usr/bin/env bash
# docs/fire_pyro.png (README, docs/lighting.md): the shared pyro with the synthetic temperature
# grid of make_pyro_fire.py, glowing as a blackbody and lit by a warm key and a blue rim light.
# Left: vdb_ewa's default; right: the reference integrator at vdb_render's converged steps
# (--method raymarch --step 0.125 --shadowstep 0.375). Each panel is the 960x540 render through
# the sRGB curve, scaled to 720x405 and labelled with its time on this machine (and the
# default's PSNR, R, G, B, A of the EXRs, against the reference). About 20 s on two cores.
#
# Needs vdb_ewa ($VDB_EWA_BIN, default vdb_ewa on PATH), /usr/bin/python3 with numpy and
# pyopenvdb, oiiotool, the DejaVu Sans font and the shared assets ($VDB_EWA_ASSETS, default
# ../shared/grids).
#
# Usage: docs/figures/make_fire_pyro.sh [--out DIR]
#   writes DIR/fire_pyro.png (default DIR: a new temporary folder; --out docs replaces the
#   committed image).
set -euo pipefail
source "$(dirname "$0")/figure_common.sh"
figure_start "$@"
python="${PYTHON:-/usr/bin/python3}"
need_tools "$ewa" "$python" oiiotool
need_asset "$assets/pyro.vdb"
need_font "$font"
figure_scratch

"$python" docs/figures/make_pyro_fire.py "$assets/pyro.vdb" "$tmp/pyro_fire.vdb"
# docs/lighting.md's command line.
shot=(-res 960x540 -translate 0.225,2.175,15.75 -lookat 0.225,2.175,-0.225 --temperature temperature
  --blackbody-intensity 10 --light 1,1,0.3,0.6,0.55,0.5 --light -1,0.3,-0.6,0.35,0.45,0.9 -q)
seconds() { # the wall time of a command, to 0.01 s
  local t0 t1
  t0=$(date +%s.%N); "$@"; t1=$(date +%s.%N)
  awk -v a="$t0" -v b="$t1" 'BEGIN {printf "%.2f", b - a}'
}
t_ewa=$(seconds "$ewa" "$tmp/pyro_fire.vdb" "$tmp/ewa.exr" "${shot[@]}")
t_ref=$(seconds "$ewa" "$tmp/pyro_fire.vdb" "$tmp/reference.exr" "${shot[@]}" --method raymarch --step 0.125 --shadowstep 0.375)
db=$({ oiiotool "$tmp/ewa.exr" --ch R,G,B,A "$tmp/reference.exr" --ch R,G,B,A --diff || true; } |
  sed -n 's/.*Peak SNR = \([0-9.]*\).*/\1/p' | awk '{printf "%.1f", $1}')
label_ewa="vdb_ewa default: $(awk -v t="$t_ewa" 'BEGIN {printf "%.1f", t}') s, $db dB"
label_ref="reference (--method raymarch --step 0.125): $(awk -v t="$t_ref" 'BEGIN {printf "%.0f", t}') s"
panel() { # EXR, label, PNG
  oiiotool "$1" --ch R,G,B --colorconvert linear sRGB --resize 720x405 \
    --text:x=15:y=30:size=20:color=1,1,1:font="$font" "$2" -o "$3"
}
panel "$tmp/ewa.exr" "$label_ewa" "$tmp/a.png"
panel "$tmp/reference.exr" "$label_ref" "$tmp/b.png"
oiiotool "$tmp/a.png" "$tmp/b.png" --mosaic 2x1 -d uint8 -o "$out/fire_pyro.png"
echo "$out/fire_pyro.png: $label_ewa; $label_ref"
