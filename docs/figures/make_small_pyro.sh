#!/usr/bin/env bash
# docs/small_pyro.png (docs/equations.md#sub-pixel-samples): the shared pyro, thick with physical
# shadows (--scatter 2 --gain 0), seen so far that a voxel spans half a pixel (160x90), over
# orange, scaled 4x (box): vdb_ewa's default without sub-pixels (--supersample 1), with them (the
# default), and the reference integrator with 64 rays a pixel (--pixel-samples 64 --step 0.25
# --shadowstep 0.375), each labelled with its brightness (sum of R, G, B) against the reference.
# About 5 s on two cores.
#
# Needs vdb_ewa ($VDB_EWA_BIN, default vdb_ewa on PATH), oiiotool, awk, the DejaVu Sans font and
# the shared assets ($VDB_EWA_ASSETS, default ../shared/grids).
#
# Usage: docs/figures/make_small_pyro.sh [--out DIR]
#   writes DIR/small_pyro.png (default DIR: a new temporary folder; --out docs replaces the
#   committed image).
set -euo pipefail
source "$(dirname "$0")/figure_common.sh"
figure_start "$@"
need_tools "$ewa" oiiotool awk
need_asset "$assets/pyro.vdb"
need_font "$font"
figure_scratch

shot=(-res 160x90 -translate 0.225,2.175,43.45 -lookat 0.225,2.175,-0.225 --scatter 2 --gain 0 -q)
"$ewa" "$assets/pyro.vdb" "$tmp/before.exr" "${shot[@]}" --supersample 1
"$ewa" "$assets/pyro.vdb" "$tmp/now.exr" "${shot[@]}"
"$ewa" "$assets/pyro.vdb" "$tmp/ref.exr" "${shot[@]}" --method raymarch --step 0.25 --shadowstep 0.375 --pixel-samples 64

# Brightness: the mean of R + G + B (ratios of means are ratios of sums).
mean_rgb() { oiiotool "$1" --ch R,G,B --printstats | awk '/Stats Avg/ {print $3 + $4 + $5}'; }
ref="$(mean_rgb "$tmp/ref.exr")"
brightness() { awk -v a="$(mean_rgb "$1")" -v r="$ref" 'BEGIN {printf "%+.0f %%", 100 * (a / r - 1)}'; }
label_before="no sub-pixels: $(brightness "$tmp/before.exr")"
label_now="default: $(brightness "$tmp/now.exr")"
panel() { # EXR, label, PNG
  oiiotool "$1" --ch R,G,B,A --pattern constant:color=0.9,0.5,0.2,1 160x90 4 --over --ch R,G,B --colorconvert linear sRGB \
    --cut 60x90+50+0 --resize:filter=box 240x360 --text:x=8:y=24:size=16:color=0,0,0:font="$font" "$2" -o "$3"
}
panel "$tmp/before.exr" "$label_before" "$tmp/a.png"
panel "$tmp/now.exr" "$label_now" "$tmp/b.png"
panel "$tmp/ref.exr" "reference" "$tmp/c.png"
oiiotool "$tmp/a.png" "$tmp/b.png" "$tmp/c.png" --mosaic:pad=4 3x1 -d uint8 -o "$out/small_pyro.png"
echo "$out/small_pyro.png: $label_before; $label_now"
