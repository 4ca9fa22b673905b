#!/usr/bin/env bash
# docs/cli.md, the command-line reference, written from the binary's own help: `vdb_ewa render
# --help` (what `vdb_ewa --help` prints), `make-grid --help`, `submit --help` and `status --help`,
# each rendered as markdown (the option names in code, the help text as it is). The help is the
# one source of the options' text (cmd/vdb_ewa/); this page is never edited by hand.
#
# Usage:
#   scripts/make-cli-doc.sh [VDB_EWA_BINARY] > docs/cli.md
#       writes the page to stdout (default binary: vdb_ewa on PATH)
#   scripts/make-cli-doc.sh --check VDB_EWA_BINARY DOC
#       regenerates into a temporary file and fails, with a diff, when DOC differs (ctest docs.cli)
#
# The text does not depend on the machine: the help is taken in the C locale, through a pipe (not
# a terminal), without COLUMNS, $OCIO or Slurm's variables; the binary's path and its version
# string are replaced should the help ever print them. Needs bash, awk, diff.
set -euo pipefail
shopt -s inherit_errexit # a failing --help fails the script, also inside $(...)

# The subcommands, in the page's order; render is the default one.
commands=(render make-grid submit status)

usage() {
  echo "usage: $0 [VDB_EWA_BINARY] > docs/cli.md" >&2
  echo "       $0 --check VDB_EWA_BINARY DOC" >&2
  exit 2
}

check="" doc=""
if [ "${1:-}" = "--check" ]; then
  [ $# -eq 3 ] || usage
  check=1 doc="$3"
  set -- "$2"
fi
[ $# -le 1 ] || usage
case "${1:-}" in -h|--help) usage ;; esac
bin="${1:-vdb_ewa}"
case "$bin" in
  */*) [ -x "$bin" ] || { echo "$0: $bin is not an executable" >&2; exit 2; } ;;
  *) command -v "$bin" >/dev/null || { echo "$0: $bin not found on PATH (give the binary: $0 build/cmd/vdb_ewa/vdb_ewa)" >&2; exit 2; } ;;
esac

if [ -n "$check" ]; then
  tmp="$(mktemp)"
  trap 'rm -f "$tmp"' EXIT
  bash "$0" "$bin" > "$tmp" || { echo "FAIL: $0 could not generate the page from $bin (above)" >&2; exit 1; }
  if diff -u --label "$doc" --label "$bin --help (regenerated)" "$doc" "$tmp" >&2; then
    echo "OK: $doc is the help of $bin"
    exit 0
  fi
  echo "FAIL: $doc differs from the help of $bin (diff above: - the file, + what the binary prints)." >&2
  echo "It is generated, never edited by hand. Regenerate it and commit it with your change:" >&2
  echo "  $0 $bin > $doc" >&2
  exit 1
fi

version="$(LC_ALL=C "$bin" --version </dev/null)"
version="${version#vdb_ewa }" # "0.1.0 (git 7d4a9a5)"
# One subcommand's help (or, with no argument, the top level's), stable across machines.
help_of() {
  local text
  text="$(unset COLUMNS LINES OCIO $(compgen -e | grep '^SLURM_' || true)
          LC_ALL=C "$bin" "$@" --help </dev/null)"
  text="${text//"$bin"/vdb_ewa}"
  [ -n "$version" ] && text="${text//"$version"/VERSION}"
  printf '%s\n' "$text" | sed 's/[[:space:]]*$//'
}

# A subcommand named in render's help that this script does not know would be left out: refuse.
render_help="$(help_of render)"
for named in $(printf '%s\n' "$render_help" | grep -oE 'vdb_ewa [a-z][a-z-]* --help' | awk '{print $2}' | sort -u); do
  case " ${commands[*]} " in
    *" $named "*) ;;
    *) echo "$0: the help names 'vdb_ewa $named', which this script does not document: add it to commands" >&2; exit 1 ;;
  esac
done

# Markdown escapes for help text: the characters markdown (GitHub's: math, strikethrough) would
# read as markup; an underscore only where it could open or close emphasis (vdb_render stays).
esc_awk='
  function esc(s,   out, i, c) {
    out = ""
    for (i = 1; i <= length(s); i++) {
      c = substr(s, i, 1)
      if (index("\\`*[]<$|&~", c) ||
          (c == "_" && !(substr(s, i - 1, 1) ~ /[A-Za-z0-9]/ && substr(s, i + 1, 1) ~ /[A-Za-z0-9]/)))
        out = out "\\"
      out = out c
    }
    return out
  }'

# CLI11's layout -> markdown. A help is: the description, "Usage: ...", sections ("Positionals:",
# "Options:") whose entries are "  NAMES[ TYPE]" padded to column 30 and the description from
# column 31 (where NAMES TYPE reaches column 30, the description starts on the next line, indented
# by 30), then a footer after a blank line. Anything else: exit 3, and the caller copies that help
# verbatim instead.
to_markdown() {
  awk "$esc_awk"'
    function names_md(s,   n, parts, i, out) {
      n = split(s, parts, ",")
      out = ""
      for (i = 1; i <= n; i++) out = out (i > 1 ? ", " : "") "`" parts[i] "`"
      return out
    }
    function entry_md(entry, desc,   sp, names, type) {
      sp = index(entry, " ")
      names = sp ? substr(entry, 1, sp - 1) : entry
      type = sp ? substr(entry, sp + 1) : ""
      return "- " names_md(names) (type != "" ? " `" type "`" : "") (desc != "" ? ": " esc(desc) : "")
    }
    function fail(i, msg) { printf "make-cli-doc: help line %d: %s: %s\n", i, msg, line[i] > "/dev/stderr"; exit 3 }
    function continuation(i) { return line[i] ~ /^                              [^ ]/ }
    { line[NR] = $0 }
    END {
      n = NR; i = 1; head = ""
      for (; i <= n && line[i] !~ /^Usage: /; i++) head = (head == "" ? line[i] : head " " line[i])
      if (i > n) fail(n, "no Usage line")
      if (head != "") print esc(head) "\n"
      print "```text\n" substr(line[i], 8) "\n```"
      footer = ""
      for (i++; i <= n; i++) {
        if (line[i] == "") continue
        if (line[i] ~ /^[A-Z][A-Za-z ]*:$/ && line[i - 1] == "") {
          print "\n**" substr(line[i], 1, length(line[i]) - 1) "**\n"
          for (i++; i <= n && line[i] != ""; i++) {
            s = line[i]
            if (s !~ /^  [^ ]/) fail(i, "not an entry")
            # The description on the same line: the name padded to column 30 (two spaces or more
            # before it, or exactly one at column 30 where no continuation line follows).
            if (length(s) > 30 && substr(s, 30, 1) == " " && substr(s, 31, 1) != " " &&
                (substr(s, 29, 1) == " " || !continuation(i + 1))) {
              entry = substr(s, 3, 28); desc = substr(s, 31)
            } else {
              entry = substr(s, 3); desc = ""
            }
            sub(/ +$/, "", entry)
            if (entry ~ /  / || entry == "") fail(i, "an entry that is not NAMES[ TYPE]")
            for (; continuation(i + 1); i++) {
              c = line[i + 1]; sub(/^ +/, "", c)
              desc = (desc == "" ? c : desc " " c)
            }
            print entry_md(entry, desc)
          }
          continue
        }
        if (line[i] ~ /^[^ ]/ && line[i - 1] == "") {
          for (; i <= n && line[i] != ""; i++) footer = (footer == "" ? line[i] : footer " " line[i])
          continue
        }
        fail(i, "unexpected line")
      }
      if (footer != "") print "\n" esc(footer)
    }'
}

escape() { awk "$esc_awk"' { print esc($0) }'; }

section() { # TITLE HELP
  local md
  printf '\n## `%s`\n\n' "$1"
  if md="$(printf '%s\n' "$2" | to_markdown)"; then
    printf '%s\n' "$md"
  else
    echo "$0: could not read the help of '$1' as CLI11's layout; it is copied verbatim" >&2
    printf '```text\n%s\n```\n' "$2"
  fi
}

summary() { # the first line of a help, the subcommand's description, as markdown
  printf '%s\n' "$1" | head -n 1 | escape
}

{
  echo "# Command-line reference"
  echo
  echo "<!-- Generated by scripts/make-cli-doc.sh from the binary's --help. Do not edit: regenerate. -->"
  echo
  echo "The help \`vdb_ewa\` prints, for every subcommand, generated from the binary by"
  echo "\`scripts/make-cli-doc.sh\`. Do not edit this page: after changing an option or its help text"
  echo "(cmd/vdb_ewa/), regenerate it from a build and commit it with the change:"
  echo
  echo '```sh'
  echo 'scripts/make-cli-doc.sh build/cmd/vdb_ewa/vdb_ewa > docs/cli.md'
  echo '```'
  echo
  echo "ctest \`docs.cli\` fails while this page differs from the binary's help."
  echo
  for cmd in "${commands[@]}"; do
    text="$(help_of "$cmd")"
    printf -- '- [`vdb_ewa %s`](#vdb_ewa-%s): %s\n' "$cmd" "$cmd" "$(summary "$text")"
  done
  echo
  if [ "$(help_of)" = "$render_help" ]; then
    echo "\`vdb_ewa --help\` prints render's help. \`vdb_ewa --version\` prints the version."
  else
    echo "\`vdb_ewa --version\` prints the version."
    section "vdb_ewa --help" "$(help_of)"
  fi
  for cmd in "${commands[@]}"; do
    section "vdb_ewa $cmd" "$(help_of "$cmd")"
  done
}
