#!/usr/bin/env bash
# Grey-box against black-box on the two multi-fault targets (issue #27): each target built twice
# with clang++ -O1, with -fsanitize-coverage=trace-pc-guard,trace-cmp and mbstorm's runtime, and
# without; each started by mbstorm (--target-cmd) and fuzzed with the same seed, until every
# planted bug is found (--max-findings) or SECONDS. Per run: cases/s, edges, and the time to
# each finding; then the coverage runs' edges over time.
# Usage: bench/run_multi_fault_coverage.sh BUILD_DIR [SECONDS] [SEED]
set -euo pipefail
build=$(cd "${1:?build dir}" && pwd)
secs=${2:-90}
seed=${3:-1}
root=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

flags=(-std=c++20 -O1 -I"$root/src")
objects=()
for src in codec/pdu_request codec/pdu_records codec/function_code slave/handler slave/data_model; do
  clang++ "${flags[@]}" -c "$root/src/$src.cpp" -o "$work/$(basename "$src").o"
  objects+=("$work/$(basename "$src").o")
done
clang -O1 -c "$root/coverage/mbstorm_coverage.c" -o "$work/runtime.o"
for name in multi_fault_server sparse_device_server; do
  clang++ "${flags[@]}" -fsanitize-coverage=trace-pc-guard,trace-cmp "$root/tests/tools/$name.cpp" \
    "${objects[@]}" "$work/runtime.o" -o "$work/$name-coverage"
  clang++ "${flags[@]}" "$root/tests/tools/$name.cpp" "${objects[@]}" -o "$work/$name-plain"
done

port=$((20000 + RANDOM % 10000))
# run TARGET BUILD PLANTED [FLAGS...]: one run, one table row.
run() {
  local name=$1 kind=$2 planted=$3; shift 3
  "$build/mbstorm" fuzz --target "127.0.0.1:$port" --target-cmd "exec $work/$name-$kind --port $port" \
    --seconds "$secs" --seed "$seed" -q --max-findings "$planted" --out "$work/out-$name-$kind" \
    --json "$work/$name-$kind.json" "$@" >/dev/null 2>&1 || true
  /usr/bin/python3 - "$work/$name-$kind.json" "$name" "$kind" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
c = j["coverage"] or {}
found = ", ".join(f"{f['root_cause']} {f['found_after_s']:.1f}"
                  for f in sorted(j["findings"], key=lambda f: f["found_after_s"]))
print(f"| {sys.argv[2]} | {sys.argv[3]} | {j['seconds']:.0f} | {j['cases']:,} | "
      f"{j['cases_per_second']:,.0f} | {c.get('edges', '—')} | {len(j['findings'])} | {found} |")
PY
}
echo "| target | build | s | cases | cases/s | edges | findings | time to each (s) |"
echo "|---|---|---:|---:|---:|---:|---:|---|"
run multi_fault_server coverage 12 --coverage
run multi_fault_server plain 12
run sparse_device_server coverage 14 --coverage
run sparse_device_server plain 14
# The rate once the findings are in: a run of SECONDS without --max-findings; from its progress
# lines, the cases run after the last finding over the time left.
for name in multi_fault_server sparse_device_server; do
  "$build/mbstorm" fuzz --target "127.0.0.1:$port" --target-cmd "exec $work/$name-coverage --port $port" \
    --seconds "$secs" --seed "$seed" --coverage --out "$work/out-$name-long" \
    --json "$work/$name-long.json" >/dev/null 2>"$work/$name-long.progress" || true
  /usr/bin/python3 - "$work/$name-long.json" "$name" "$work/$name-long.progress" <<'PY'
import json, re, sys
j = json.load(open(sys.argv[1]))
last = max(j["findings"], key=lambda f: f["found_after_s"])
progress = [(float(t), int(n)) for t, n in
            re.findall(r"\[\s*([0-9.]+)s\] ([0-9]+) cases", open(sys.argv[3]).read())]
t0, n0 = next((t, n) for t, n in progress if t >= last["found_after_s"] + 1)
t1, n1 = progress[-1]
rate = (n1 - n0) / (t1 - t0)
print(f"{sys.argv[2]} coverage, {j['seconds']:.0f} s: {j['cases']:,} cases ({j['cases_per_second']:,.0f}/s), "
      f"{len(j['findings'])} findings, the last at {last['found_after_s']:.1f} s; "
      f"{rate:,.0f} cases/s after it; {j['coverage']['edges']} edges")
PY
done
for name in multi_fault_server sparse_device_server; do
  /usr/bin/python3 - "$work/$name-coverage.json" "$name" <<'PY'
import json, sys
points = json.load(open(sys.argv[1]))["coverage"]["edges_over_time"]
at = lambda s: max([e for t, e in points if t <= s] or [0])
print(f"{sys.argv[2]} edges at 1/2/5/10/20/40/80 s: " + ", ".join(str(at(s)) for s in (1, 2, 5, 10, 20, 40, 80)))
PY
done
