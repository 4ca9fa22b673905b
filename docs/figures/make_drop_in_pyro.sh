#!/usr/bin/env bash
# docs/drop_in_pyro.png (README): the shared pyro on one vdb_render command line, three panels
# through the same sRGB transform: vdb_render's defaults, vdb_render's converged image
# (-step 0.125 -shadowstep 0.375) and vdb_ewa's default, each labelled with its PSNR (R, G, B, A
# of the EXRs) against the converged image. Each panel is the middle 380 columns of a 960x540
# render, 4 pixels apart. About 10 s on two cores (the converged image takes most of it).
#
# Needs vdb_ewa ($VDB_EWA_BIN, default vdb_ewa on PATH), vdb_render (libopenvdb-tools), oiiotool,
# the DejaVu Sans font and the shared assets ($VDB_EWA_ASSETS, default ../shared/grids).
#
# Usage: docs/figures/make_drop_in_pyro.sh [--out DIR]
#   writes DIR/drop_in_pyro.png (default DIR: a new temporary folder; --out docs replaces the
#   committed image).
set -euo pipefail
source "$(dirname "$0")/figure_common.sh"
figure_start "$@"
need_tools "$ewa" vdb_render oiiotool
need_asset "$assets/pyro.vdb"
need_font "$font"
figure_scratch

# The README's command line, in vdb_render's syntax, for both renderers.
shot=(-res 960x540 -translate 0.225,2.175,15.75 -lookat 0.225,2.175,-0.225
  -light 0.3,0.3,0,1,0.6,0.3 -scatter 1.5,1.0,0.5 -absorb 0.1,0.2,0.3)
vdb_render "$assets/pyro.vdb" "$tmp/defaults.exr" "${shot[@]}"
vdb_render "$assets/pyro.vdb" "$tmp/converged.exr" "${shot[@]}" -step 0.125 -shadowstep 0.375
"$ewa" "$assets/pyro.vdb" "$tmp/ewa.exr" "${shot[@]}" -q

# PSNR of R, G, B, A against the converged image (oiiotool exits non-zero when images differ).
psnr() {
  { oiiotool "$1" --ch R,G,B,A "$tmp/converged.exr" --ch R,G,B,A --diff || true; } |
    sed -n 's/.*Peak SNR = \([0-9.]*\).*/\1/p' | awk '{printf "%.1f", $1}'
}
label_defaults="vdb_render defaults ($(psnr "$tmp/defaults.exr") dB)"
label_ewa="vdb_ewa default ($(psnr "$tmp/ewa.exr") dB)"
panel() { # EXR, label, PNG
  oiiotool "$1" --ch R,G,B --colorconvert linear sRGB --cut 380x540+290+0 \
    --text:x=10:y=30:size=20:color=1,1,1:font="$font" "$2" -o "$3"
}
panel "$tmp/defaults.exr" "$label_defaults" "$tmp/a.png"
panel "$tmp/converged.exr" "vdb_render converged" "$tmp/b.png"
panel "$tmp/ewa.exr" "$label_ewa" "$tmp/c.png"
oiiotool "$tmp/a.png" "$tmp/b.png" "$tmp/c.png" --mosaic:pad=4 3x1 -d uint8 -o "$out/drop_in_pyro.png"
echo "$out/drop_in_pyro.png: $label_defaults; $label_ewa"
