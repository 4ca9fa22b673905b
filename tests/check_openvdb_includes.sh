#!/usr/bin/env bash
# ctest source.openvdb_includes: the library is compiled with hidden visibility, so its OpenVDB
# headers must come through lib/support/openvdb.h, openvdb_tools.h, openvdb_morphology.h or openvdb_point_index.h
# (default visibility; see there). Fails on any other #include <openvdb/...> in lib/ or include/.
set -euo pipefail
cd "$1"
if grep -rnE '^\s*#\s*include\s*[<"]openvdb/' lib include \
    | grep -vE '^(lib/support/openvdb(_tools|_morphology|_point_index)?\.h|include/vdb_ewa/openvdb_grid\.h):'; then
  echo "FAIL: include OpenVDB through lib/support/openvdb.h, openvdb_tools.h, openvdb_morphology.h or openvdb_point_index.h" >&2
  exit 1
fi
echo "OK: every OpenVDB include of the library has default visibility"
