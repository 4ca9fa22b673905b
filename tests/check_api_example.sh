#!/usr/bin/env bash
# ctest docs.api_example: docs/api.md quotes tests/consumer/plugin_example.cpp (built and run
# against the installed package by install.consumer) verbatim, as the first ```cpp block after
# the heading "## A complete plugin-style example". Fails with a diff when they differ.
set -euo pipefail
cd "$1"
quoted=$(awk '/^## A complete plugin-style example/ { section = 1; next }
              section && !inside && /^```cpp$/ { inside = 1; next }
              inside && /^```$/ { exit }
              inside { print }' docs/api.md)
if [ -z "$quoted" ]; then
  echo "FAIL: docs/api.md has no \`\`\`cpp block under '## A complete plugin-style example'" >&2
  exit 1
fi
if ! diff -u tests/consumer/plugin_example.cpp <(printf '%s\n' "$quoted") >&2; then
  echo "FAIL: docs/api.md does not quote tests/consumer/plugin_example.cpp verbatim (diff above)" >&2
  exit 1
fi
echo "OK: docs/api.md quotes tests/consumer/plugin_example.cpp verbatim"
