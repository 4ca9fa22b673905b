#!/usr/bin/env bash
# docs/lod_dolly.png (docs/performance.md, level of detail): frames 3 to 6 of bench.py
# stability's dolly on the shared pyro (24 frames at 480x270, the README camera moved away from
# its target, 2.5x the distance over the 24 frames) in --quality draft. Top row: draft before
# the continuous level of detail (commit c4fc237, one block size per leaf: the plume pops
# between frames 4 and 5); bottom row: draft as the given vdb_ewa renders it. Each tile is
# 241x231 pixels of the frame (from x 120, y 20) through the sRGB curve, clamped to [0, 1].
# A few seconds on two cores.
#
# The top row needs a vdb_ewa built from commit c4fc237 (--before-bin); without it only the
# bottom row is written. To build one outside the shared build folders:
#   git worktree add /tmp/vdb_ewa-c4fc237 c4fc237
#   cmake -S /tmp/vdb_ewa-c4fc237 -B /tmp/vdb_ewa-c4fc237/build -DCMAKE_BUILD_TYPE=Release
#   cmake --build /tmp/vdb_ewa-c4fc237/build -j2 --target vdb_ewa
#   (then --before-bin /tmp/vdb_ewa-c4fc237/build/cmd/vdb_ewa/vdb_ewa)
#
# Needs vdb_ewa ($VDB_EWA_BIN, default vdb_ewa on PATH), oiiotool and the shared assets
# ($VDB_EWA_ASSETS, default ../shared/grids).
#
# Usage: docs/figures/make_lod_dolly.sh [--out DIR] [--before-bin VDB_EWA_AT_C4FC237]
#   writes DIR/lod_dolly.png (default DIR: a new temporary folder; --out docs replaces the
#   committed image, which only makes sense with --before-bin).
set -euo pipefail
source "$(dirname "$0")/figure_common.sh"
out="" before=""
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    --before-bin) before="$2"; shift 2 ;;
    *) echo "usage: $0 [--out DIR] [--before-bin VDB_EWA_AT_C4FC237]" >&2; exit 2 ;;
  esac
done
ewa="$(ewa_bin)"
out="$(out_dir "$out")"
[ -n "$before" ] && before="$(path_of "$before")"
absolute_assets
cd "$(dirname "$0")/../.."
assets="$(assets_dir)"
need_tools "$ewa" oiiotool ${before:+"$before"}
need_asset "$assets/pyro.vdb"
mkdir -p "$out"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

# bench.py camera_path(..., "dolly", f, 24) for pyro's camera: the eye moves from the target
# (0.225,2.175,-0.225) along +z, at 15.975 x 2.5^(f/23).
row() { # binary, name: four tiles
  local bin="$1" name="$2" f eye tiles=()
  for f in 3 4 5 6; do
    eye=$(awk -v f="$f" 'BEGIN {printf "0.225000,2.175000,%.6f", -0.225 + 15.975 * 2.5 ^ (f / 23)}')
    "$bin" render --exr-type float "$assets/pyro.vdb" "$tmp/$name$f.exr" -res 480x270 \
      -translate "$eye" -lookat 0.225000,2.175000,-0.225000 --quality draft -q
    oiiotool "$tmp/$name$f.exr" --ch R,G,B --clamp:min=0:max=1 --colorconvert linear sRGB \
      --cut 241x231+120+20 -o "$tmp/$name$f.png"
    tiles+=("$tmp/$name$f.png")
  done
  oiiotool "${tiles[@]}" --mosaic 4x1 -o "$tmp/$name.png"
}
row "$ewa" now
if [ -n "$before" ]; then
  row "$before" before
  oiiotool "$tmp/before.png" "$tmp/now.png" --mosaic 1x2 -d uint8 -o "$out/lod_dolly.png"
else
  oiiotool "$tmp/now.png" -d uint8 -o "$out/lod_dolly.png"
  echo "$0: no --before-bin: the bottom row only" >&2
fi
echo "$out/lod_dolly.png"
