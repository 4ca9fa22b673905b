# shellcheck shell=bash
# docs/figures/figure_common.sh: the helpers the figure generators share (README.md here). Not
# run by itself: each make_*.sh sources it before its cd to the project root, as
#   source "$(dirname "$0")/figure_common.sh"
# and its messages name the generator ($0). It only defines functions.

# A path made absolute against the current folder, before the generator's cd.
absolute() { case "$1" in /*) echo "$1" ;; */*) echo "$PWD/$1" ;; *) echo "$1" ;; esac; } # a bare name: PATH
path_of() { case "$1" in /*) echo "$1" ;; *) echo "$PWD/$1" ;; esac; }

# The vdb_ewa binary: $VDB_EWA_BIN, else $VDB_EWA, else vdb_ewa on PATH (absolute, or a bare name).
ewa_bin() { absolute "${VDB_EWA_BIN:-${VDB_EWA:-vdb_ewa}}"; }

# The output folder: --out's DIR (argument 1) made absolute, else a new temporary folder.
out_dir() { path_of "${1:-$(mktemp -d)}"; }

# $VDB_EWA_ASSETS, when set, made absolute (and exported, for bench/bench.py), before the cd.
absolute_assets() {
  if [ -n "${VDB_EWA_ASSETS:-}" ]; then
    VDB_EWA_ASSETS="$(path_of "$VDB_EWA_ASSETS")"
    export VDB_EWA_ASSETS
  fi
}

# For bench/bench.py (run from the project root): $VDB_EWA_BIN (ewa_bin) and $VDB_EWA_ASSETS made
# absolute and exported, before the cd.
bench_env() {
  VDB_EWA_BIN="$(ewa_bin)"
  export VDB_EWA_BIN
  absolute_assets
}

# The options of a generator that takes --out DIR only: sets out.
# shellcheck disable=SC2034 # out is the caller's
out_option() {
  out=""
  while [ $# -gt 0 ]; do
    case "$1" in
      --out) out="$2"; shift 2 ;;
      *) echo "usage: $0 [--out DIR]" >&2; exit 2 ;;
    esac
  done
}

# After the cd (paths relative to the project root): the shared assets and the label font.
assets_dir() { echo "${VDB_EWA_ASSETS:-../shared/grids}"; }
figure_font() { echo "${FIGURE_FONT:-/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf}"; }

# The start of a generator that takes --out DIR only and renders with vdb_ewa: its options
# (out_option), then ewa, out (absolute), assets and font set, $VDB_EWA_ASSETS made absolute, and
# the cd to the project root.
# shellcheck disable=SC2034 # ewa, out, assets and font are the caller's
figure_start() {
  out_option "$@"
  ewa="$(ewa_bin)"
  out="$(out_dir "$out")"
  absolute_assets
  cd "$(dirname "$0")/../.." || exit 1
  assets="$(assets_dir)"
  font="$(figure_font)"
}

# After the checks: the output folder made, and tmp a scratch folder removed on exit.
# shellcheck disable=SC2034 # tmp is the caller's
figure_scratch() {
  mkdir -p "$out"
  tmp="$(mktemp -d)"
  trap 'rm -rf "$tmp"' EXIT
}

# Checks that exit 1 with a message naming the generator.
need_tools() { # TOOL...: each a command on PATH or an executable path
  local tool
  for tool in "$@"; do
    command -v "$tool" >/dev/null || { echo "$0: $tool not found" >&2; exit 1; }
  done
}
need_asset() { # FILE
  [ -f "$1" ] || { echo "$0: $1 not found (set VDB_EWA_ASSETS)" >&2; exit 1; }
}
need_font() { # FILE
  [ -f "$1" ] || { echo "$0: font $1 not found (fonts-dejavu-core, or set FIGURE_FONT)" >&2; exit 1; }
}
need_matplotlib() { # PYTHON
  "$1" -c "import matplotlib" 2>/dev/null ||
    { echo "$0: $1 has no matplotlib (apt-get install python3-matplotlib)" >&2; exit 1; }
}
