#!/usr/bin/env bash
# The Debian package for a studio's machines: builds vdb_ewa (Release) in a tree of its own
# configured for the prefix /usr (default build-pkg/, built only as far as it is out of date), then
# cpack (cmake/vdb_ewa_package.cmake) writes vdb_ewa_VERSION_ARCH.deb, package vdb-ewa, into the
# current folder or --out DIR: /usr/bin/vdb_ewa, libvdb_ewa in /usr/lib/<multiarch> with its headers
# and CMake package, the Python module in /usr/lib/python3/dist-packages; its Depends from
# dpkg-shlibdeps. Installs the Debian packages it needs first (dpkg-dev among them). docs/install.md.
#   bash scripts/package.sh [--out DIR] [--build-dir DIR] [--maintainer "Name <email>"] [--homepage URL]
#   sudo apt-get install ./vdb_ewa_0.1.0_amd64.deb     and later     sudo apt-get remove vdb-ewa
set -euo pipefail
out=$(pwd)
build=build-pkg
cache_args=()
while [ "$#" -gt 0 ]; do
  case $1 in
    --out|--build-dir|--maintainer|--homepage)
      [ "$#" -ge 2 ] || { echo "package: $1 needs a value" >&2; exit 2; }
      case $1 in
        --out) out=$2 ;;
        --build-dir) build=$2 ;;
        --maintainer) cache_args+=("-DVDB_EWA_PACKAGE_MAINTAINER=$2") ;;
        --homepage) cache_args+=("-DVDB_EWA_PACKAGE_HOMEPAGE=$2") ;;
      esac
      shift 2 ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) echo "package: unknown argument '$1' (usage: scripts/package.sh [--out DIR] [--build-dir DIR] [--maintainer \"Name <email>\"] [--homepage URL])" >&2; exit 2 ;;
  esac
done
mkdir -p "$out"
out=$(cd "$out" && pwd)
case $build in
  /*) ;;
  *) build=$(cd "$(dirname "$0")/.." && pwd)/$build ;;
esac
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
# A new tree builds what the package holds, no tests; an existing one keeps its options.
[ -f "$build/CMakeCache.txt" ] || cache_args+=(-DVDB_EWA_BUILD_TESTS=OFF)
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX=/usr "${cache_args[@]}"
cmake --build "$build" -j"$(nproc)"

rm -rf "$build/cpack"
cpack --config "$build/CPackConfig.cmake" -B "$build/cpack"
deb=$(find "$build/cpack" -maxdepth 1 -name 'vdb_ewa_*.deb' -print -quit)
[ -n "$deb" ] || { echo "package: cpack wrote no vdb_ewa_*.deb in $build/cpack" >&2; exit 1; }
mv -f "$deb" "$out/"
deb=$out/$(basename "$deb")
dpkg-deb --field "$deb" Package Version Architecture Depends
echo "package: wrote $deb (install: sudo apt-get install $deb; remove: sudo apt-get remove vdb-ewa)"
