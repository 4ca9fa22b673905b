#!/usr/bin/env bash
# docs/point_light_pyro.png: the shared pyro made thin and lit from inside by a point light,
# vdb_ewa's default (left) beside the reference integrator (right). Needs vdb_ewa (or
# $VDB_EWA), oiiotool and the shared assets ($VDB_EWA_ASSETS, default ../shared/grids).
set -euo pipefail
cd "$(dirname "$0")/../.."
ewa="${VDB_EWA:-vdb_ewa}"
assets="${VDB_EWA_ASSETS:-../shared/grids}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
shot=(-res 480x270 -translate 0.225,2.175,15.75 -lookat 0.225,2.175,-0.225 --scatter 0.05 --absorb 0.01
  --light 0.3,0.3,0,0.2,0.2,0.2 --point-light 0.225,2.5,-0.225,6,3,1.2)
"$ewa" "$assets/pyro.vdb" "$tmp/splat.exr" "${shot[@]}"
"$ewa" "$assets/pyro.vdb" "$tmp/reference.exr" "${shot[@]}" --method raymarch --step 0.125 --shadowstep 0.125
for f in splat reference; do oiiotool "$tmp/$f.exr" --ch R,G,B --colorconvert linear sRGB -o "$tmp/$f.png"; done
oiiotool "$tmp/splat.png" "$tmp/reference.png" --mosaic 2x1 -o docs/point_light_pyro.png
