#!/usr/bin/env bash
# docs/equations.md maps the paper's equations to code: every function its tables name in the
# code column (a `name` or `Class::name` in backticks) must exist in lib/ or include/ as a
# function or method (followed by an opening parenthesis somewhere in the sources).
set -euo pipefail
root="$1"
doc="$root/docs/equations.md"
missing=0
checked=0
# Code column: the last cell of each table row.
while IFS= read -r name; do
  base="${name##*::}"
  checked=$((checked + 1))
  if ! grep -rqE "\b${base}\s*\(" "$root/lib" "$root/include"; then
    echo "docs/equations.md names \`$name\`, which is not a function in lib/ or include/"
    missing=$((missing + 1))
  fi
done < <(grep -E '^\|' "$doc" | grep -vE '^\|[ -]*\|' | awk -F'|' '{print $(NF-1)}' \
  | grep -oE '`[A-Za-z_][A-Za-z0-9_]*(::[A-Za-z_][A-Za-z0-9_]*)*`' | tr -d '`' | sort -u)
if [ "$checked" -eq 0 ]; then
  echo "no function names found in $doc"
  exit 1
fi
echo "$checked names checked, $missing missing"
[ "$missing" -eq 0 ]
