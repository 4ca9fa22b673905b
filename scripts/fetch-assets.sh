#!/usr/bin/env bash
# Fetch the shared real-world assets that the tests and benchmarks read from $VDB_EWA_ASSETS,
# from their public sources (the table of ../shared/grids/README.md), into DIR (default
# ../shared/grids from the project root).
#
# - Six files are downloaded from GitHub. Each is checked to be a VDB file (not an HTML page or
#   a Git LFS pointer) and compared with the SHA-256 of the copy the tests were written
#   against. A different checksum is a warning: the source may have changed since.
# - bunny_levelset.vdb and brain_mri.vdb are built from Debian packages with pyopenvdb: the
#   Stanford bunny of glmark2-data and VolPack's MRI example of libvolpack1-dev. Each package is
#   used where it is installed; otherwise it is fetched with `apt-get download` and unpacked
#   into a temporary folder (nothing is installed). Without /usr/bin/python3 and pyopenvdb
#   (python3-openvdb, python3-numpy), the script prints the steps instead.
# - Files already in DIR are kept; --force fetches them again.
#
# Every file that cannot be fetched or built gets one line on stderr, and the script exits 1.
#
# Licences: the GitHub files come with no licence file. Use them for testing only, and do not
# copy them into the project. The bunny's data is GPL-3+ (glmark2-data). The brain is VolPack's
# example data (see the copyright file of libvolpack1-dev). This script checks no licence.
#
# Usage: scripts/fetch-assets.sh [--force] [DIR]
set -euo pipefail

force=""
dir=""
for arg in "$@"; do
  case "$arg" in
    --force) force=1 ;;
    -h | --help) sed -n '2,23p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "usage: $0 [--force] [DIR]" >&2; exit 2 ;;
    *) [ -z "$dir" ] || { echo "usage: $0 [--force] [DIR]" >&2; exit 2; }; dir="$arg" ;;
  esac
done
root="$(cd "$(dirname "$0")/.." && pwd)"
dir="${dir:-$root/../shared/grids}"
mkdir -p "$dir" || { echo "fetch-assets: cannot create $dir" >&2; exit 1; }
dir="$(cd "$dir" && pwd)"
python="${PYTHON:-/usr/bin/python3}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
failed=0
fail() { # one line for a file that could not be fetched or built
  echo "fetch-assets: $1: $2" >&2
  failed=$((failed + 1))
}
wanted() { # true when $dir/$1 is to be made
  if [ -z "$force" ] && [ -s "$dir/$1" ]; then
    echo "fetch-assets: $1: already in $dir (kept; --force fetches it again)"
    return 1
  fi
}

# name | repository | commit (HEAD: the default branch) | path in the repository | SHA-256 of the tested copy
downloads="
smoke.vdb|Ibukhvalov/render|HEAD|data/vdbAssets/smoke.vdb|09e5727dab14d1ef46532b9b731a8d2de4c1de333a97c443516fd8ae8ca8c03b
pyro.vdb|Elyg/OpenVDB_Visualizer|HEAD|data/pyro.vdb|70404783783c32cf5aabdc1f3d0e8975f9c2c80ae59561437b085759444d1a5f
pig.vdb|Elyg/OpenVDB_Visualizer|HEAD|data/pig.vdb|bd7588c35ec333196e6098d955d6e1fd077af160035d09c02218a5c8736e1a51
fog_tommy_v5.vdb|Elyg/OpenVDB_Visualizer|HEAD|data/fogTommy.vdb|3e10745efbdd56bd81fba78282af7b3ffe61b5d8664815cc370ecb9e96da5288
smoke_double.vdb|daichi-ishida/VSCode-CMakeTemplate|7866843deea79a2e1b1ebeb46492cd029e1871e5|smoke.vdb|cfc65c633b483471efb741b86d83f71fe343115d5d089ae6dd1fe6b149da38f6
cube_levelset.vdb|Ibukhvalov/render|HEAD|data/vdbAssets/cube.vdb|e5ed2748c07bc64aa38b6df6812008bed840d7734ce460ad447d0f86ef5e6da4
"

download() { # URL FILE: curl or wget, 15 s to connect, the error's last line in $tmp/why
  if command -v curl >/dev/null; then
    curl -fsSL --connect-timeout 15 --retry 1 -o "$2" "$1" 2>"$tmp/why"
  elif command -v wget >/dev/null; then
    wget -q --timeout=15 --tries=2 -O "$2" "$1" 2>"$tmp/why"
  else
    echo "neither curl nor wget is installed" >"$tmp/why"
    return 1
  fi
}

is_vdb() { # OpenVDB's magic number, 0x56444220, as a little-endian int64
  [ "$(head -c 8 "$1" | od -An -tx1 | tr -d ' \n')" = "2042445600000000" ]
}

while IFS='|' read -r name repo commit path sum; do
  [ -n "$name" ] || continue
  wanted "$name" || continue
  url="https://raw.githubusercontent.com/$repo/$commit/$path"
  part="$tmp/$name"
  if ! download "$url" "$part"; then
    fail "$name" "cannot fetch $url ($(tail -n 1 "$tmp/why" 2>/dev/null | tr -d '\r'))"
    continue
  fi
  if head -c 200 "$part" | grep -q "git-lfs"; then
    fail "$name" "$url is a Git LFS pointer, not the file (fetch it from a clone with git lfs pull)"
    continue
  fi
  if ! is_vdb "$part"; then
    fail "$name" "$url is not a VDB file ($(head -c 40 "$part" | tr -c '[:print:]' ' '))"
    continue
  fi
  got="$(sha256sum "$part" | cut -d' ' -f1)"
  if [ "$got" != "$sum" ]; then
    echo "fetch-assets: warning: $name: SHA-256 $got differs from the tested copy's $sum (the source changed?)" >&2
  fi
  mv "$part" "$dir/$name"
  echo "fetch-assets: $name: $(stat -c %s "$dir/$name") bytes from $repo:$path"
done <<<"$downloads"

# The file PATH of Debian package PACKAGE: the installed one, else from `apt-get download` into
# $tmp (unpacked, not installed). Prints the path; empty where neither works.
debian_file() {
  local package="$1" path="$2" deb
  if [ -f "$path" ]; then echo "$path"; return; fi
  if [ -f "$path.gz" ]; then gzip -dc "$path.gz" >"$tmp/$(basename "$path")" && echo "$tmp/$(basename "$path")"; return; fi
  mkdir -p "$tmp/deb"
  (cd "$tmp/deb" && apt-get download "$package" >/dev/null 2>"$tmp/why") || return 0
  deb="$(ls "$tmp/deb/${package}"_*.deb 2>/dev/null | head -n 1 || true)"
  [ -n "$deb" ] && dpkg-deb -x "$deb" "$tmp/deb/root" 2>/dev/null || return 0
  if [ -f "$tmp/deb/root$path" ]; then
    echo "$tmp/deb/root$path"
  elif [ -f "$tmp/deb/root$path.gz" ]; then
    gzip -dc "$tmp/deb/root$path.gz" >"$tmp/$(basename "$path")" && echo "$tmp/$(basename "$path")"
  fi
}

have_pyopenvdb() { "$python" -c "import numpy, pyopenvdb" 2>/dev/null; }

# bunny_levelset.vdb: glmark2-data's bunny.obj as a level set (grid 'surface', voxel 1/128,
# narrow band 3 voxels each side; 942,554 active voxels).
if wanted bunny_levelset.vdb; then
  obj="$(debian_file glmark2-data /usr/share/glmark2/models/bunny.obj)"
  if [ -z "$obj" ]; then
    fail bunny_levelset.vdb "cannot get glmark2-data's models/bunny.obj (apt-get install glmark2-data, or apt-get download it)"
  elif ! have_pyopenvdb; then
    fail bunny_levelset.vdb "needs $python with numpy and pyopenvdb (apt-get install python3-numpy python3-openvdb); then: read $obj's 'v' and 'f' lines, pyopenvdb.FloatGrid.createLevelSetFromPolygons(points, triangles=faces - 1, transform=pyopenvdb.createLinearTransform(voxelSize=1/128), halfWidth=3), name it 'surface', write it"
  elif "$python" - "$obj" "$tmp/bunny_levelset.vdb" <<'EOF'; then
import sys
import numpy as np
import pyopenvdb as vdb

points, faces = [], []
for line in open(sys.argv[1]):
    words = line.split()
    if words and words[0] == "v":
        points.append([float(x) for x in words[1:4]])
    elif words and words[0] == "f":
        faces.append([int(w.split("/")[0]) - 1 for w in words[1:4]])
grid = vdb.FloatGrid.createLevelSetFromPolygons(np.array(points, np.float32), triangles=np.array(faces, np.uint32),
                                                transform=vdb.createLinearTransform(voxelSize=1.0 / 128.0), halfWidth=3.0)
grid.name = "surface"
vdb.write(sys.argv[2], grids=[grid])
print(f"fetch-assets: bunny_levelset.vdb: {grid.activeVoxelCount()} active voxels (the tested copy: 942554)")
EOF
    mv "$tmp/bunny_levelset.vdb" "$dir/bunny_levelset.vdb"
  else
    fail bunny_levelset.vdb "the conversion of $obj failed (above)"
  fi
fi

# brain_mri.vdb: VolPack's brainsmall.den (a 62-byte header, then 128 x 128 x 84 bytes, x
# fastest) divided by its largest value, values below 0.1 inactive (grid 'density', fog
# volume, voxel 1; 274,487 active voxels). The tested copy also differs from this recipe in
# 970 voxels of one 16 x 32 x 8 block (x 80-95, y 72-103, z 24-31); its source is not known.
if wanted brain_mri.vdb; then
  den="$(debian_file libvolpack1-dev /usr/share/doc/libvolpack1-dev/examples/brainsmall.den)"
  if [ -z "$den" ]; then
    fail brain_mri.vdb "cannot get libvolpack1-dev's examples/brainsmall.den (apt-get install libvolpack1-dev, or apt-get download it)"
  elif ! have_pyopenvdb; then
    fail brain_mri.vdb "needs $python with numpy and pyopenvdb (apt-get install python3-numpy python3-openvdb); then: skip $den's 62-byte header, read 84 x 128 x 128 bytes (z, y, x), transpose to (x, y, z), divide by the largest value, set values below 0.1 to 0, FloatGrid.copyFromArray, name 'density', class fog volume, write it"
  elif "$python" - "$den" "$tmp/brain_mri.vdb" <<'EOF'; then
import struct
import sys
import numpy as np
import pyopenvdb as vdb

raw = open(sys.argv[1], "rb").read()
swap = struct.unpack("<h", raw[:2])[0] != 1  # VolPack's map_version: 1, or 0x0100 byte-swapped
order = ">" if swap else "<"
header = struct.unpack(order + "28h", raw[2:58])
nx, ny, nz = header[24:27]                      # map_len
count = struct.unpack(order + "i", raw[58:62])[0]
if count != nx * ny * nz or len(raw) < 62 + count:
    sys.exit(f"fetch-assets: brain_mri.vdb: {sys.argv[1]} has an inconsistent header")
voxels = np.frombuffer(raw[62:62 + count], np.uint8).reshape(nz, ny, nx).transpose(2, 1, 0)
density = (voxels / float(voxels.max())).astype(np.float32)
density[density < 0.1] = 0.0
grid = vdb.FloatGrid(0.0)
grid.copyFromArray(np.ascontiguousarray(density), ijk=(0, 0, 0), tolerance=0.0)
grid.name = "density"
grid.gridClass = vdb.GridClass.FOG_VOLUME
vdb.write(sys.argv[2], grids=[grid])
print(f"fetch-assets: brain_mri.vdb: {grid.activeVoxelCount()} active voxels (the tested copy: 274487)")
EOF
    mv "$tmp/brain_mri.vdb" "$dir/brain_mri.vdb"
  else
    fail brain_mri.vdb "the conversion of $den failed (above)"
  fi
fi

echo "fetch-assets: licences: the GitHub files come with no licence file: for testing only, do not copy them into the project; bunny: GPL-3+ (glmark2-data); brain: VolPack's example (libvolpack1-dev's copyright file)"
if [ "$failed" -gt 0 ]; then
  echo "fetch-assets: $failed file(s) missing from $dir" >&2
  exit 1
fi
echo "fetch-assets: every asset is in $dir (export VDB_EWA_ASSETS=$dir where it is not ../shared/grids)"
