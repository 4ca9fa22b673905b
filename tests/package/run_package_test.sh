#!/usr/bin/env bash
# ctest package.deb (tests/CMakeLists.txt): cpack packages this build tree as the Debian package
# (cmake/vdb_ewa_package.cmake) without building anything, checks its fields and files (no test
# binaries), extracts it with dpkg -x into a temporary root, and runs what it extracted: the CLI's
# --version and a small render (EXR and PNG: the image module beside the library), and the Python
# module imported by Debian's python3 from the extracted dist-packages, rendering too.
# Exit 77 (skipped) where cpack, dpkg-deb or dpkg-shlibdeps (dpkg-dev) is missing.
set -euo pipefail
if [ "$#" -ne 7 ]; then
  echo "usage: $0 CMAKE CPACK BUILD_DIR WORK_DIR SOURCE_DIR VERSION PYTHON" >&2
  exit 2
fi
cmake=$1 cpack=$2 build=$3 work=$4 source=$5 version=$6 python=${7:-/usr/bin/python3}
SECONDS=0
for tool in "$cpack" dpkg dpkg-deb dpkg-shlibdeps; do
  command -v "$tool" >/dev/null || { echo "SKIP: $tool not found (Debian's dpkg-dev and cmake: scripts/install-deps.sh)"; exit 77; }
done
rm -rf "$work"
mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }

# cpack's own install step first builds the tree's preinstall target, which would re-run CMake and
# rebuild whatever changed since the build (a commit moves the version, an edited source) while
# other tests run its binaries. So: the same install, cmake --install with DESTDIR into the
# packaging prefix (CPACK_PACKAGING_INSTALL_PREFIX, /usr) and stripped as CPACK_STRIP_FILES asks,
# then cpack packages that folder with the tree's CPackConfig.cmake (fields, dpkg-shlibdeps, shlibs).
prefix=$(sed -n 's/^set(CPACK_PACKAGING_INSTALL_PREFIX "\(.*\)")$/\1/p' "$build/CPackConfig.cmake")
echo "== cmake --install $build --prefix ${prefix:=/usr} --strip (DESTDIR=$work/stage)"
DESTDIR=$work/stage "$cmake" --install "$build" --prefix "$prefix" --strip >"$work/install.log" ||
  { cat "$work/install.log"; fail "cmake --install failed"; }
echo "== cpack --config $build/CPackConfig.cmake"
"$cpack" --config "$build/CPackConfig.cmake" -B "$work/cpack" -D CPACK_INSTALL_CMAKE_PROJECTS= \
  -D "CPACK_INSTALLED_DIRECTORIES=$work/stage;/" >"$work/cpack.log" 2>&1 || { cat "$work/cpack.log"; fail "cpack failed"; }
deb=$work/cpack/vdb_ewa_${version}_$(dpkg --print-architecture).deb
[ -f "$deb" ] || { ls "$work/cpack"; fail "cpack wrote no $(basename "$deb")"; }
echo "$(basename "$deb"): $(du -k "$deb" | cut -f1) KiB"

echo "== control fields"
dpkg-deb --field "$deb" Package Version Architecture Maintainer Section Depends | tee "$work/fields.txt"
field() { dpkg-deb --field "$deb" "$1"; }
[ "$(field Package)" = vdb-ewa ] || fail "Package is '$(field Package)', not vdb-ewa"
[ "$(field Version)" = "$version" ] || fail "Version is '$(field Version)', not $version"
[ -n "$(field Maintainer)" ] && [ -n "$(field Description)" ] && [ -n "$(field Section)" ] || fail "Maintainer, Description or Section is empty"
for dependency in libopenvdb libtbb libopencolorio libopenexr 'libc6 '; do
  field Depends | grep -q "$dependency" || fail "Depends names no $dependency (dpkg-shlibdeps)"
done

echo "== files"
dpkg-deb --fsys-tarfile "$deb" | tar -t | sed 's|^\./|/|' | grep -v '/$' >"$work/files.txt"
# Only what `cmake --install` puts under /usr: the CLI, the libraries, headers, the CMake package, the
# Python module, the copyright file. A test binary, a build path or /usr/local is a failure.
allowed='^/usr/(bin/vdb_ewa|lib/([a-z0-9_]+-linux-gnu/)?(libvdb_ewa\.so(\.[0-9.]+)?|libvdb_ewa_images\.so|cmake/vdb_ewa/vdb_ewa[A-Za-z-]*\.cmake)|include/vdb_ewa/[a-z_]+\.h|lib/python3(\.[0-9]+)?/dist-packages/vdb_ewa(\.cpython-[0-9a-z_-]+\.so|\.pyi)|share/doc/vdb-ewa/copyright)$'
if grep -Ev "$allowed" "$work/files.txt" >"$work/unexpected.txt"; then
  cat "$work/unexpected.txt" >&2
  fail "the package holds files that are not vdb_ewa's install (above)"
fi
for pattern in '^/usr/bin/vdb_ewa$' '/libvdb_ewa\.so\.[0-9.]+$' '/libvdb_ewa_images\.so$' '^/usr/include/vdb_ewa/vdb_ewa\.h$' \
               '/cmake/vdb_ewa/vdb_ewaConfig\.cmake$' '/cmake/vdb_ewa/vdb_ewaTargets\.cmake$' '^/usr/share/doc/vdb-ewa/copyright$'; do
  grep -Eq "$pattern" "$work/files.txt" || fail "no file matches $pattern"
done
echo "$(wc -l <"$work/files.txt") files, all under /usr, none of the tests"

root=$work/root
dpkg -x "$deb" "$root"
lib=$(dirname "$(find "$root/usr/lib" -name 'libvdb_ewa.so.*' -print -quit)")
cloud=$source/grids/cloud.vdb

echo "== extracted CLI (LD_LIBRARY_PATH=$lib)"
out=$(cd "$work" && LD_LIBRARY_PATH=$lib "$root/usr/bin/vdb_ewa" --version)
echo "$out"
case $out in
  "vdb_ewa $version (git "*")") ;;
  *) fail "--version printed '$out', not 'vdb_ewa $version (git COMMIT)'" ;;
esac
# The extracted library, not the build tree's or an installed one.
LD_LIBRARY_PATH=$lib ldd "$root/usr/bin/vdb_ewa" | grep -F "libvdb_ewa.so" | grep -qF "$lib/" ||
  fail "the extracted vdb_ewa does not load the extracted libvdb_ewa.so"
(cd "$work" && LD_LIBRARY_PATH=$lib "$root/usr/bin/vdb_ewa" render "$cloud" "$work/cli.exr" --preview "$work/cli.png" \
   --res 64x36 --translate 1.5,0.8,4.5 -q) || fail "the extracted vdb_ewa could not render $cloud"
[ -s "$work/cli.exr" ] && [ -s "$work/cli.png" ] || fail "the extracted vdb_ewa wrote no EXR or PNG"
echo "rendered cli.exr and cli.png"

module=$(find "$root/usr/lib" -name 'vdb_ewa.cpython-*.so' -print -quit)
if [ -z "$module" ]; then
  echo "== no Python module in this package (VDB_EWA_BUILD_PYTHON off): not imported"
else
  dist=$(dirname "$module")
  echo "== extracted Python module ($python, PYTHONPATH=$dist)"
  [ -f "$dist/vdb_ewa.pyi" ] || fail "vdb_ewa.pyi is not beside the module"
  field Depends | grep -q python3-numpy || fail "Depends names no python3-numpy"
  (cd "$work" && PYTHONPATH=$dist LD_LIBRARY_PATH=$lib "$python" -s - "$dist" "$version" "$cloud" "$work/python.exr" <<'EOF'
import sys
import vdb_ewa
dist, version, cloud, out = sys.argv[1:]
assert vdb_ewa.__file__.startswith(dist + "/"), vdb_ewa.__file__
assert vdb_ewa.__version__ == version, vdb_ewa.__version__
frame = vdb_ewa.render(cloud, res="64x36", translate=(1.5, 0.8, 4.5))
assert frame.beauty.shape == (36, 64, 4), frame.beauty.shape
assert frame.beauty[..., 3].max() > 0.1, "an empty image"
frame.write(out)
print("vdb_ewa", vdb_ewa.__version__, "from", vdb_ewa.__file__, "rendered", out)
EOF
  ) || fail "the extracted Python module could not be imported or render"
fi
echo "package.deb: ${SECONDS} s"
