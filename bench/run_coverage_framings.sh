#!/usr/bin/env bash
# Grey-box against black-box on targets that do not speak MBAP (issue #27): the device of
# tests/tools/coverage_device.c (two planted crashes, each needing two fields equal to
# constants at once) speaking RTU over TCP, then RTU and ASCII on a socat pty pair at 115,200
# baud, built with clang and mbstorm's coverage runtime (coverage mode) or without coverage
# (black-box mode), started by mbstorm (--target-cmd). Per run: cases/s, edges, corpus, and the
# time to each planted crash (a coverage run stops at the second, --max-findings 2).
# Usage: bench/run_coverage_framings.sh BUILD_DIR [SECONDS] [SEEDS]
set -euo pipefail
build=$(cd "${1:?build dir}" && pwd)
secs=${2:-60}
seeds=${3:-1}
here=$(cd "$(dirname "$0")" && pwd)
device="$here/../tests/tools/coverage_device.c"
work=$(mktemp -d)
socat_pid=""
trap '[ -n "$socat_pid" ] && kill "$socat_pid" 2>/dev/null; rm -rf "$work"' EXIT

clang -O1 -fsanitize-coverage=trace-pc-guard,trace-cmp -c "$device" -o "$work/device.o"
clang -O1 -c "$here/../coverage/mbstorm_coverage.c" -o "$work/runtime.o"
clang "$work/device.o" "$work/runtime.o" -o "$work/device-coverage"
clang -O1 "$device" -o "$work/device-plain"
port=$((20000 + RANDOM % 10000))

# run FRAMING MODE SEED: one run, one table row.
run() {
  local framing=$1 mode=$2 seed=$3 target flags=() binary=device-plain
  [ "$mode" = coverage ] && { binary=device-coverage; flags=(--coverage --max-findings 2); }
  if [ "$framing" = rtu-over-tcp ]; then
    target=(--transport rtu-over-tcp --target "127.0.0.1:$port")
    cmd="exec $work/$binary --port $port --framing rtu"
  else
    rm -f "$work/line_a" "$work/line_b"
    socat pty,raw,echo=0,link="$work/line_a" pty,raw,echo=0,link="$work/line_b" 2>/dev/null &
    socat_pid=$!
    sleep 0.5
    target=(--serial "$work/line_b" --framing "${framing#serial-}" --baud 115200 --parity none
      --timeout 300ms)
    cmd="exec $work/$binary --tty $work/line_a --framing ${framing#serial-}"
  fi
  "$build/mbstorm" fuzz "${target[@]}" --target-cmd "$cmd" --seconds "$secs" --seed "$seed" -q \
    --no-model --max-connections 0 --out "$work/out-$framing-$mode-$seed" \
    --json "$work/r.json" "${flags[@]}" >/dev/null 2>&1 || true
  [ -n "$socat_pid" ] && { kill "$socat_pid" 2>/dev/null; wait "$socat_pid" 2>/dev/null || true; socat_pid=""; }
  /usr/bin/python3 - "$work/r.json" "$framing" "$mode" "$seed" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
c = j["coverage"] or {}
found = ", ".join(f"{f['root_cause']} at {f['found_after_s']:.2f} s" for f in j["findings"])
print(f"| {sys.argv[2]} | {sys.argv[3]} | {sys.argv[4]} | {j['seconds']:.1f} | {j['cases']:,} | "
      f"{j['cases_per_second']:,.0f} | {c.get('edges', '—')} | {c.get('corpus', '—')} | "
      f"{found or 'none'} |")
PY
}
echo "| framing | mode | seed | s | cases | cases/s | edges | corpus | findings (time to each) |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---|"
for framing in rtu-over-tcp serial-rtu serial-ascii; do
  for seed in $(seq 1 "$seeds"); do run "$framing" coverage "$seed"; done
  run "$framing" black-box 1
done
