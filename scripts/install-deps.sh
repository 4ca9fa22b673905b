#!/usr/bin/env bash
# Install the Debian 12 packages vdb_ewa needs to build, test and benchmark.
# Idempotent: installs only what is missing. Uses sudo when not run as root. With --test, also
# what the Python module's, the Blender add-on's and the Slurm tests need (scripts/test.sh). With --bench, also
# what bench/bench.py's image analyses need (numpy, pyopenvdb, OpenImageIO's Python module,
# matplotlib) and bench/roofline (Google Benchmark, xsimd).
set -euo pipefail
packages=(
  cmake g++ make pkg-config
  libopenvdb-dev libboost-iostreams-dev libopenexr-dev libimath-dev libtbb-dev libglm-dev
  libopencolorio-dev libopenimageio-dev
  libdeflate-dev     # zip EXRs deflated in a third to half of zlib's time (lib/output/exr_zip_writer.h)
  zlib1g-dev         # the tests inflate those chunks with zlib, as OpenEXR reads them
  libcli11-dev nlohmann-json3-dev libgtest-dev
  pybind11-dev python3-dev python3-numpy  # the Python module (python/)
  libhwy-dev         # Highway: the SIMD rasteriser's per-target code and run-time dispatch
  libopenvdb-tools   # vdb_render: the peer the tests and benchmarks compare against
  openimageio-tools  # oiiotool: EXR -> PNG previews and image diffs
  clang libclang-rt-14-dev  # the sanitized test build and the libFuzzer harnesses (tests/fuzz)
  dpkg-dev           # dpkg-shlibdeps: the .deb's Depends (scripts/package.sh, ctest package.deb)
)
if [ "${1:-}" = "--test" ]; then
  # The Python module's test reads EXRs and writes VDBs with OpenVDB's own binding; the Blender
  # add-on's tests render in Blender (plugins/blender), its viewport test in a virtual X server (xvfb-run).
  packages+=(python3-openvdb python3-openimageio blender xvfb)
  # tests/slurm: a one-node Slurm cluster (controller, node daemon, client commands, munge) runs
  # vdb_ewa submit's job arrays.
  packages+=(slurmctld slurmd slurm-client munge)
fi
if [ "${1:-}" = "--bench" ]; then
  packages+=(python3-numpy python3-openvdb python3-openimageio python3-matplotlib libbenchmark-dev libxsimd-dev)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "${#missing[@]}" -eq 0 ]; then
  exit 0
fi
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
echo "install-deps: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
