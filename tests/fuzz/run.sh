#!/usr/bin/env bash
# Fuzzing campaign: build the libFuzzer harnesses (clang, ASan+UBSan) and run each for SECONDS,
# side by side, each on a working copy of its seed corpus. Findings (crash-*, timeout-*, oom-*,
# leak-*) land in build-san/fuzz/artifacts; each becomes a file of tests/fuzz/corpus/NAME so that
# ctest (fuzz.NAME) replays it from then on. Usage: tests/fuzz/run.sh [SECONDS] [HARNESS...]
# (default: 3600 s, all of vdb_file job_file options).
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds=${1:-3600}
shift || true
harnesses=("$@")
[ "${#harnesses[@]}" -gt 0 ] || harnesses=(vdb_file job_file options)
build=build-san
# A campaign needs the whole library instrumented for coverage (scripts/test.sh's replay does not).
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DVDB_EWA_BUILD_TESTS=ON -DVDB_EWA_SANITIZE=ON -DVDB_EWA_BUILD_FUZZERS=ON -DVDB_EWA_FUZZ_COVERAGE=ON >/dev/null
cmake --build "$build" -j"$(nproc)" --target "${harnesses[@]/#/fuzz_}" >/dev/null
# The sanitizers' options are compiled in (tests/sanitizer/default_options.cpp).
mkdir -p "$build/fuzz/artifacts"
for h in "${harnesses[@]}"; do
  work=$build/fuzz/corpus-$h
  mkdir -p "$work"
  cp -n tests/fuzz/corpus/"$h"/* "$work"/ 2>/dev/null || true
  # -fork=1: the campaign goes on after a finding. -timeout: one input may take at most 60 s
  # (a 1M-kernel frame takes 3-8 s under ASan); -rss_limit_mb: the harnesses render under a
  # 256 MB budget, so 3 GB is a runaway. Inputs up to 64 KB (the seeds are 0.5-22 KB).
  "$build/tests/fuzz/fuzz_$h" "$work" -fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1 \
    -max_total_time="$seconds" -timeout=60 -rss_limit_mb=3072 -max_len=65536 \
    -artifact_prefix="$build/fuzz/artifacts/$h-" >"$build/fuzz/$h.log" 2>&1 &
done
status=0
wait || status=$?
for h in "${harnesses[@]}"; do
  # The fork driver's last status line: "#RUNS: cov: N ft: N corp: N exec/s N oom/timeout/crash: A/B/C time: Ts".
  echo "fuzz_$h: $(grep -E '^#[0-9]+: cov:' "$build/fuzz/$h.log" | tail -1)"
done
echo "findings: $(ls "$build/fuzz/artifacts" | wc -l) in $build/fuzz/artifacts"
ls "$build/fuzz/artifacts"
exit "$status"
