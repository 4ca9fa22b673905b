#!/usr/bin/env bash
# ctest install.consumer (tests/CMakeLists.txt): install the build into a fresh prefix, check the
# symbols libvdb_ewa.so exports, run the installed CLI, then configure, build and run the consumer
# project next to this script (plugin_example.cpp) against the installed package only.
set -euo pipefail
if [ "$#" -ne 9 ]; then
  echo "usage: $0 CMAKE NM BUILD_DIR CONFIG WORK_DIR LIBDIR GENERATOR CXX WARNING_FLAGS" >&2
  exit 2
fi
cmake=$1 nm=$2 build=$3 config=$4 work=$5 libdir=$6 generator=$7 cxx=$8 warning_flags=$9
here=$(cd "$(dirname "$0")" && pwd)
prefix=$work/prefix
rm -rf "$work"
mkdir -p "$work"

echo "== cmake --install into $prefix"
"$cmake" --install "$build" --prefix "$prefix" ${config:+--config "$config"} >"$work/install.log"

echo "== exported dynamic symbols of $prefix/$libdir/libvdb_ewa.so"
lib=$prefix/$libdir/libvdb_ewa.so
[ -f "$lib" ] || { echo "FAIL: $lib not installed" >&2; exit 1; }
# "ADDRESS TYPE NAME" lines, names demangled.
"$nm" -D --defined-only --demangle "$lib" | cut -d' ' -f3- >"$work/exports.txt"
echo "$(wc -l <"$work/exports.txt") symbols exported"
api='^((typeinfo|typeinfo name|vtable) for )?vdb_ewa::'
if grep -Ev "$api" "$work/exports.txt" >"$work/foreign.txt" ||
   grep -E "${api}detail::" "$work/exports.txt" >>"$work/foreign.txt"; then
  echo "FAIL: symbols outside the vdb_ewa API are exported (OpenVDB, std::, vdb_ewa::detail...):" >&2
  head -20 "$work/foreign.txt" >&2
  exit 1
fi
# Private members of exported classes are VDB_EWA_LOCAL.
if grep -E 'vdb_ewa::GridSource::Impl::|vdb_ewa::Renderer::(renderLevelSet|renderFogVolume|addIsoSurface)\(' \
     "$work/exports.txt" >"$work/private.txt"; then
  echo "FAIL: private members are exported:" >&2
  cat "$work/private.txt" >&2
  exit 1
fi
for symbol in 'vdb_ewa::Renderer::Renderer(' 'vdb_ewa::Renderer::render(' 'vdb_ewa::gridSourceFromOpenVDB(' \
              'vdb_ewa::Renderer::renderFrame(' 'typeinfo for vdb_ewa::Error' 'typeinfo for vdb_ewa::Cancelled'; do
  grep -qF "$symbol" "$work/exports.txt" || { echo "FAIL: $symbol is not exported" >&2; exit 1; }
done

echo "== installed CLI"
"$prefix/bin/vdb_ewa" --version
# A .png goes through OpenImageIO's module, libvdb_ewa_images.so, found beside the installed library.
[ -f "$prefix/$libdir/libvdb_ewa_images.so" ] || { echo "FAIL: libvdb_ewa_images.so is not installed" >&2; exit 1; }
LD_LIBRARY_PATH= "$prefix/bin/vdb_ewa" "$here/../../grids/cloud.vdb" "$work/installed.png" -res 32x18 -q || exit 1
[ -s "$work/installed.png" ] || { echo "FAIL: the installed CLI wrote no .png" >&2; exit 1; }

# The Python module, where the build has one: imported from the prefix alone (its RPATH finds
# libvdb_ewa.so there), its stub beside it.
module=$(find "$prefix" -name 'vdb_ewa.cpython-*.so' -print -quit)
if [ -n "$module" ]; then
  echo "== installed Python module $module"
  [ -f "$(dirname "$module")/vdb_ewa.pyi" ] || { echo "FAIL: vdb_ewa.pyi is not installed beside the module" >&2; exit 1; }
  (cd "$work" && PYTHONPATH="$(dirname "$module")" LD_LIBRARY_PATH= /usr/bin/python3 -c \
    'import vdb_ewa, sys; assert vdb_ewa.__file__.startswith(sys.argv[1]), vdb_ewa.__file__; print("vdb_ewa", vdb_ewa.__version__)' "$prefix")
fi

echo "== consumer project"
# No build type (-O0): the OpenVDB headers compile a third faster, and the rendering runs in the
# installed, optimised library anyway.
"$cmake" -S "$here" -B "$work/build" -G "$generator" -DCMAKE_CXX_COMPILER="$cxx" \
  -DCMAKE_BUILD_TYPE= -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_CXX_FLAGS="$warning_flags" \
  >"$work/configure.log" || { cat "$work/configure.log"; exit 1; }
"$cmake" --build "$work/build" || exit 1
"$work/build/plugin_example"
