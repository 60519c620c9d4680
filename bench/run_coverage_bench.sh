#!/usr/bin/env bash
# Grey-box against black-box (issue #27) on tests/tools/coverage_device.c, whose two planted
# crashes each need two or three fields equal to constants at once: the device built three
# ways (clang with mbstorm's coverage runtime, AFL++'s afl-clang-fast, and no coverage), each
# started by mbstorm (--target-cmd). Per run: cases/s, edges, corpus, and the time to each
# planted crash. Coverage mode over seeds 1..5 (SECONDS/3 each), then one run of SECONDS each.
# Usage: bench/run_coverage_bench.sh BUILD_DIR [SECONDS]
set -euo pipefail
build=$(cd "${1:?build dir}" && pwd)
secs=${2:-60}
here=$(cd "$(dirname "$0")" && pwd)
device="$here/../tests/tools/coverage_device.c"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

clang -O1 -g -fsanitize-coverage=trace-pc-guard,trace-cmp -c "$device" -o "$work/device.o"
clang -O1 -c "$here/../coverage/mbstorm_coverage.c" -o "$work/runtime.o"
clang "$work/device.o" "$work/runtime.o" -o "$work/device-coverage"
clang -O1 -g "$device" -o "$work/device-plain"
AFL_QUIET=1 afl-clang-fast -O1 -g "$device" -o "$work/device-afl"

port=$((20000 + RANDOM % 10000))
# run NAME BINARY SEED SECONDS [FLAGS...]: one run, one line.
run() {
  local name=$1 binary=$2 seed=$3 s=$4; shift 4
  "$build/mbstorm" fuzz --target "127.0.0.1:$port" --target-cmd "exec $work/$binary --port $port" \
    --seconds "$s" --seed "$seed" -q --no-model --max-connections 0 --out "$work/out-$name-$seed" \
    --json "$work/$name-$seed.json" "$@" >/dev/null 2>&1 || true
  /usr/bin/python3 - "$work/$name-$seed.json" "$name" "$seed" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
c = j["coverage"] or {}
found = ", ".join(f"{f['root_cause']} at {f['found_after_s']:.2f} s" for f in j["findings"])
print(f"| {sys.argv[2]} | {sys.argv[3]} | {j['seconds']:.0f} | {j['cases_per_second']:,.0f} | "
      f"{c.get('edges', '—')} | {c.get('corpus', '—')} | {found or 'none'} |")
PY
}
echo "| build | seed | s | cases/s | edges | corpus | findings (time to each) |"
echo "|---|---:|---:|---:|---:|---:|---|"
for seed in 1 2 3 4 5; do run coverage device-coverage "$seed" $((secs / 3)) --coverage; done
run coverage device-coverage 1 "$secs" --coverage
run afl-clang-fast device-afl 1 "$secs" --coverage
run black-box device-plain 1 "$secs"
