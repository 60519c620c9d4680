#!/usr/bin/env bash
# Runs every Google Benchmark binary briefly to prove it works; no timing assertions.
set -euo pipefail
cd "$(dirname "$0")/.."
found=0
for bin in build/release/bench/*_bench; do
  [ -x "$bin" ] || continue
  found=1
  echo "bench smoke: ${bin##*/}"
  "$bin" --benchmark_min_time=0.01 >/dev/null
done
[ $found -eq 1 ] || { echo "bench smoke: no benchmarks built" >&2; exit 1; }
echo "bench smoke: ok"
