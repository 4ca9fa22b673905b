#!/usr/bin/env bash
# ctest source.stage_doors: each pipeline stage under lib/ (source, shading, projection, raster,
# reference) is entered through one header, lib/<stage>/<stage>.h (docs/architecture.md). Fails
# on any include of another stage's inner header from lib/ or tests/, and on any file of lib/
# below the orchestrator (the stages, the frame parts) that includes the orchestrator's header,
# vdb_ewa/renderer.h (what they fill, RenderStats, is in vdb_ewa/render_stats.h).
set -euo pipefail
cd "$1"
stages="source shading projection raster reference"
bad=0
for stage in $stages; do
  # Inner headers of $stage included from outside lib/$stage.
  if grep -rnE "^\s*#\s*include\s*\"$stage/[a-z_]+\.h\"" lib tests --include='*.h' --include='*.cpp' \
      | grep -v "^lib/$stage/" | grep -v "\"$stage/$stage\.h\""; then
    bad=1
  fi
done
if [ "$bad" -ne 0 ]; then
  echo "FAIL: include another stage through its door, lib/<stage>/<stage>.h" >&2
  exit 1
fi
# The orchestrator, Renderer, is renderer.cpp and streamed_frame.cpp (its streamed fog volume);
# scene.cpp, the Scene that drives it, stands above it.
if grep -rnE "^\s*#\s*include\s*[<\"]vdb_ewa/renderer\.h[>\"]" lib --include='*.h' --include='*.cpp' \
    | grep -vE "^lib/(renderer|streamed_frame|scene)\.cpp:"; then
  echo "FAIL: only the orchestrator includes vdb_ewa/renderer.h; include vdb_ewa/render_stats.h for RenderStats" >&2
  exit 1
fi
echo "OK: every stage is entered through its door header, and none includes the orchestrator"
