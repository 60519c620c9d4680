#!/usr/bin/env bash
# Builds the libFuzzer harnesses (clang 14) and runs each for N seconds from its seed corpus,
# two at a time. Any crash fails the run; the crashing input is left in build/fuzz/findings/.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}

cmake --preset fuzz >/dev/null
cmake --build --preset fuzz -j "$(nproc)"

mkdir -p build/fuzz/findings
harnesses=()
for bin in build/fuzz/fuzz/fuzz_*; do [ -x "$bin" ] && harnesses+=("$bin"); done
[ ${#harnesses[@]} -gt 0 ] || { echo "run-fuzz: no harnesses built" >&2; exit 1; }

run_one() {
  local bin=$1 name=${1##*/fuzz_}
  local corpus=fuzz/corpus/$name work=build/fuzz/corpus-work/$name
  mkdir -p "$work"
  local seeds=(); [ -d "$corpus" ] && seeds+=("$corpus")
  if "$bin" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
       -dict=fuzz/modbus.dict -artifact_prefix="build/fuzz/findings/$name-" \
       "$work" "${seeds[@]}" >"build/fuzz/$name.log" 2>&1; then
    echo "fuzz $name: clean ($(grep -m1 -o 'stat::number_of_executed_units: *[0-9]*' "build/fuzz/$name.log" | grep -o '[0-9]*$') runs)"
  else
    echo "fuzz $name: FAILED" >&2; tail -n 40 "build/fuzz/$name.log" >&2; return 1
  fi
}

status=0
pids=()
for bin in "${harnesses[@]}"; do
  run_one "$bin" & pids+=($!)
  if [ ${#pids[@]} -ge 2 ]; then wait "${pids[0]}" || status=1; pids=("${pids[@]:1}"); fi
done
for p in "${pids[@]}"; do wait "$p" || status=1; done
exit $status
