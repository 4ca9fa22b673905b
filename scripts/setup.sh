#!/usr/bin/env bash
# One command from a fresh Debian 12 machine to an installed vdb_ewa: install the Debian packages,
# build (Release, in build/), install into a prefix, and render the sample cloud from grids/ to
# cloud.exr with the installed binary. The prefix (default /usr/local; --prefix DIR or
# $VDB_EWA_PREFIX) gets bin/vdb_ewa, the library with its headers and CMake package
# (find_package(vdb_ewa)), and the Python module vdb_ewa (for /usr/local, where Debian's
# /usr/bin/python3 and Blender import it). Installs through sudo when not root and the prefix is
# not writable. docs/install.md.
#   bash scripts/setup.sh [--prefix DIR] [--build-dir DIR (in the repository; default build)]
#   bash scripts/setup.sh --uninstall [--build-dir DIR]   removes what DIR/install_manifest.txt lists
set -euo pipefail
prefix=${VDB_EWA_PREFIX:-/usr/local}
build=build
uninstall=0
while [ "$#" -gt 0 ]; do
  case $1 in
    --prefix) [ "$#" -ge 2 ] || { echo "setup: --prefix needs a folder" >&2; exit 2; }; prefix=$2; shift 2 ;;
    --prefix=*) prefix=${1#--prefix=}; shift ;;
    --build-dir) [ "$#" -ge 2 ] || { echo "setup: --build-dir needs a folder" >&2; exit 2; }; build=$2; shift 2 ;;
    --uninstall) uninstall=1; shift ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) echo "setup: unknown argument '$1' (usage: scripts/setup.sh [--prefix DIR] [--build-dir DIR] [--uninstall])" >&2; exit 2 ;;
  esac
done
case $prefix in
  /*) ;;
  *) prefix=$(pwd)/$prefix ;;
esac
prefix=${prefix%/}
prefix=${prefix:-/}
case $build in
  /*) ;;
  *) build=$(cd "$(dirname "$0")/.." && pwd)/$build ;;
esac
cd "$(dirname "$0")/.."

# sudo for the install when not root and the prefix (or its first existing parent) is not writable.
sudo=""
if [ "$(id -u)" -ne 0 ]; then
  existing=$prefix
  while [ ! -e "$existing" ]; do existing=$(dirname "$existing"); done
  [ -w "$existing" ] || sudo="sudo"
fi
# ld.so's cache lists /usr/local/lib and /usr/lib: refresh it for hosts linking libvdb_ewa.so (the
# installed vdb_ewa and Python module find it through their RPATH anyway).
refresh_ld_cache() {
  case $prefix in
    /usr|/usr/local) $sudo ldconfig ;;
  esac
}

if [ "$uninstall" -eq 1 ]; then
  manifest=$build/install_manifest.txt
  [ -f "$manifest" ] || { echo "setup: $manifest not found: nothing installed from this build" >&2; exit 1; }
  echo "setup: removing the $(wc -l <"$manifest") files of $manifest"
  tr '\n' '\0' <"$manifest" | $sudo xargs -0 rm -f --
  # vdb_ewa's own folders, and lib/cmake and share/doc where they are left empty.
  grep -E '/(vdb_ewa|vdb-ewa)/[^/]+$' "$manifest" | xargs -r -n1 dirname | sort -u |
    while read -r dir; do
      $sudo rmdir "$dir" 2>/dev/null || continue
      case $(basename "$(dirname "$dir")") in cmake|doc) $sudo rmdir "$(dirname "$dir")" 2>/dev/null || true ;; esac
    done
  refresh_ld_cache
  $sudo rm -f "$manifest"
  exit 0
fi

bash scripts/install-deps.sh
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DVDB_EWA_BUILD_TESTS=OFF -DCMAKE_INSTALL_PREFIX="$prefix"
cmake --build "$build" -j"$(nproc)"
echo "setup: installing into $prefix${sudo:+ (sudo)}"
$sudo cmake --install "$build"
refresh_ld_cache

"$prefix/bin/vdb_ewa" --version
"$prefix/bin/vdb_ewa" render grids/cloud.vdb cloud.exr --translate 1.5,0.8,4.5 --res 960x540 -v
echo "setup: wrote $(pwd)/cloud.exr"

# Where the installed pieces are, and what a new shell needs to see them.
if [ "$(command -v vdb_ewa || true)" != "$prefix/bin/vdb_ewa" ]; then
  echo "setup: $prefix/bin is not first on PATH: export PATH=\"$prefix/bin:\$PATH\""
fi
module=$(grep -m1 '/vdb_ewa\.cpython-[^/]*\.so$' "$build/install_manifest.txt" || true)
if [ -n "$module" ] && [ -x /usr/bin/python3 ]; then
  found=$(cd / && env -u PYTHONPATH /usr/bin/python3 -c 'import vdb_ewa; print(vdb_ewa.__file__)' 2>/dev/null || true)
  if [ "$found" = "$module" ]; then
    echo "setup: /usr/bin/python3 (and Blender's Python) import vdb_ewa from $(dirname "$module")"
  else
    echo "setup: the Python module is in $(dirname "$module"): export PYTHONPATH=\"$(dirname "$module")\""
  fi
fi
