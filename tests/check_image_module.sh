#!/usr/bin/env bash
# ctest cli.image_module: OpenImageIO is loaded only for images that need it (lib/output/image_codec.h).
# - the CLI's start-up maps no OpenImageIO library (ldd);
# - a .png output loads libvdb_ewa_images.so and is written;
# - with the module missing (libvdb_ewa.so copied alone into a folder), a .png output fails before
#   the render, in one line naming the module, exit 4, no file; an .exr output still renders.
set -euo pipefail
cli="$1" grid="$2"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

if ldd "$cli" | grep -q libOpenImageIO; then fail "$cli loads OpenImageIO at start-up"; fi

"$cli" "$grid" "$tmp/ok.png" -res 32x18 2>/dev/null || fail "a .png output failed"
[ -s "$tmp/ok.png" ] || fail "no .png written"

library=$(ldd "$cli" | awk '/libvdb_ewa\.so/ {print $3}')
[ -n "$library" ] || fail "ldd names no libvdb_ewa.so"
mkdir "$tmp/alone"
cp "$(readlink -f "$library")" "$tmp/alone/$(basename "$library")"
set +e
LD_LIBRARY_PATH="$tmp/alone" "$cli" "$grid" "$tmp/missing.png" -res 32x18 2>"$tmp/err"
code=$?
set -e
[ "$code" -eq 4 ] || { cat "$tmp/err" >&2; fail "exit $code without the module, expected 4"; }
[ ! -e "$tmp/missing.png" ] || fail "a file was written without the module"
grep -q "vdb_ewa_images.so" "$tmp/err" || { cat "$tmp/err" >&2; fail "the error does not name the module"; }
[ "$(wc -l <"$tmp/err")" -eq 1 ] || { cat "$tmp/err" >&2; fail "more than one line on stderr"; }
grep -q "done" "$tmp/err" && fail "rendered before failing"
LD_LIBRARY_PATH="$tmp/alone" "$cli" "$grid" "$tmp/alone.exr" -res 32x18 2>/dev/null || fail "an .exr output failed without the module"
[ -s "$tmp/alone.exr" ] || fail "no .exr written without the module"
echo "OK: OpenImageIO loads on the first image that needs it, and its absence is one line before the render"
