#!/bin/bash
# Issue 53's figures: a real Mantaflow fire cache (bench/bake_mantaflow_fire.py, frame 20 of a
# 64-cell bake) rendered from its side at 240x135 by the splatter and the reference, still and
# with motion blur over one frame, its velocities read in their own unit (--velocity-scale 2.5 x
# the voxel, 0.078125) and raw (as world units a second, 32x too fast). PSNR (RGB) against the
# reference (--blur-samples 64). Usage: bench/mantaflow_fire.sh [CACHE_DIR] (baked if absent).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
bin=${VDB_EWA_BIN:-$here/../build-tests/cmd/vdb_ewa/vdb_ewa}
cache=${1:-/tmp/mantaflow_fire}
frame=$cache/data/fluid_data_0020.vdb
[ -f "$frame" ] || blender --factory-startup -b --python "$here/bake_mantaflow_fire.py" -- "$cache" >/dev/null
out=$(mktemp -d)
# shellcheck disable=SC2054 # commas separate the values of one option
cam=(-res 240x135 -translate 1,-5,1 -lookat 1,1,1 --up 0,0,1 --density-grid density --emission-grid flame
  --emission-color 1,0.35,0.08 --emission-intensity 0.03)
psnr() { oiiotool "$1" --ch R,G,B "$2" --ch R,G,B --diff 2>/dev/null | sed -n 's/.*Peak SNR = \([0-9.]*\).*/\1/p' | xargs printf '%.1f'; }
echo "# $frame, 240x135; reference: --method raymarch --blur-samples 64"
echo "| velocities | frame | splatter | PSNR vs reference (dB) |"
echo "|---|---|---|---|"
"$bin" "$frame" "$out/still_ref.exr" "${cam[@]}" --method raymarch >/dev/null 2>&1
for q in default high; do
  "$bin" "$frame" "$out/still_$q.exr" "${cam[@]}" --quality $q >/dev/null 2>&1
  echo "| | still | $q | $(psnr "$out/still_$q.exr" "$out/still_ref.exr") |"
done
for scale in 0.078125 1; do
  # shellcheck disable=SC2054
  blur=(--velocity-grid velocity --shutter -0.5,0.5 --velocity-scale "$scale")
  "$bin" "$frame" "$out/ref_$scale.exr" "${cam[@]}" "${blur[@]}" --method raymarch --blur-samples 64 >/dev/null 2>&1
  echo "| --velocity-scale $scale | the reference's own blur | | $(psnr "$out/still_ref.exr" "$out/ref_$scale.exr") |"
  for q in "--quality default" "--quality default --motion-light still" "--quality high" "--quality final"; do
    # shellcheck disable=SC2086 # $q is several options
    "$bin" "$frame" "$out/t.exr" "${cam[@]}" "${blur[@]}" $q >/dev/null 2>&1
    echo "| --velocity-scale $scale | blurred | ${q#--quality } | $(psnr "$out/t.exr" "$out/ref_$scale.exr") |"
  done
done
rm -rf "$out"
