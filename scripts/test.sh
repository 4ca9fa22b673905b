#!/usr/bin/env bash
# One command to build vdb_ewa with its tests and run them (ctest), twice: the Release build,
# then the same suite built by clang under AddressSanitizer and UndefinedBehaviorSanitizer, with
# the fuzzers' seed corpora replayed (tests/fuzz). Installs what is missing. The shared assets
# in $VDB_EWA_ASSETS (default ../shared/grids) are used when present.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh --test
cmake -S . -B build-tests -DCMAKE_BUILD_TYPE=Release -DVDB_EWA_BUILD_TESTS=ON -DVDB_EWA_WARNINGS_AS_ERRORS=ON
cmake --build build-tests -j"$(nproc)"
(cd build-tests && ctest --output-on-failure -j"$(nproc)")
cmake -S . -B build-san -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DVDB_EWA_BUILD_TESTS=ON \
  -DVDB_EWA_SANITIZE=ON -DVDB_EWA_BUILD_FUZZERS=ON -DVDB_EWA_FUZZ_COVERAGE=OFF
cmake --build build-san -j"$(nproc)"
(cd build-san && ctest --output-on-failure -j"$(nproc)")
