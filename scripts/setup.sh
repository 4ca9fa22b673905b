#!/usr/bin/env bash
# One command from a fresh Debian 12 machine to an EXR: install the packages, build
# (Release) and render the sample cloud from grids/ to cloud.exr.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DVDB_EWA_BUILD_TESTS=OFF
cmake --build build -j"$(nproc)"
build/cmd/vdb_ewa/vdb_ewa render grids/cloud.vdb cloud.exr --translate 1.5,0.8,4.5 --res 960x540 -v
echo "setup: wrote $(pwd)/cloud.exr"
