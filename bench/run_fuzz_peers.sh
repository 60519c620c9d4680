#!/usr/bin/env bash
# Fuzzer precision and budget against servers nobody here wrote (pymodbus 3.0's asyncio server,
# a libmodbus 3.1 server, and the same with a sparse map from its unit tests), the second
# multi-fault target (tests/tools/sparse_device_server.cpp, 12 planted bugs, under its own 20 ms
# supervisor) and the first (tests/tools/multi_fault_server.cpp, 11 planted bugs, restarted
# through --restart-cmd): per peer the wall time against --seconds,
# cases/s, the findings (one line per root cause, for hand triage), restarts per root cause;
# then, on the multi-fault target, the time to find each planted bug, structured vs --naive.
# Usage: bench/run_fuzz_peers.sh BUILD_DIR [SECONDS]
set -euo pipefail
build=$(cd "${1:?build dir}" && pwd)
secs=${2:-60}
here=$(cd "$(dirname "$0")" && pwd)
mb="$build/mbstorm"
work=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; pkill -f "multi_fault_server --port $mf_port" 2>/dev/null || true; rm -rf "$work"' EXIT
mf_port=$((20000 + RANDOM % 10000))

# wait_port FILE: the "PORT n" a server printed.
wait_port() { for _ in $(seq 100); do grep -q PORT "$1" && break; sleep 0.1; done; awk '/PORT/{print $2}' "$1"; }

# fuzz NAME TARGET [ARGS...]: one timed run; prints the summary table rows.
fuzz() {
  local name=$1 target=$2; shift 2
  local t0=$SECONDS
  "$mb" fuzz --target "$target" --seconds "$secs" --seed 1 -q --out "$work/$name" \
    --json "$work/$name.json" "$@" > /dev/null 2>&1 || true
  local wall=$((SECONDS - t0))
  /usr/bin/python3 - "$name" "$work/$name.json" "$wall" "$secs" <<'PY'
import json, sys
name, path, wall, secs = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
j = json.load(open(path))
print(f"{name}: --seconds {secs}, wall {wall} s (campaign {j['seconds']:.1f} s), "
      f"{j['cases']} cases = {j['cases_per_second']:.0f} cases/s, {len(j['findings'])} findings, "
      f"{j['restarts']} restarts, {j['skipped_known']} skipped as known, "
      f"{j['suspects_left']} suspects left at the deadline")
m = j.get("model")
if m:
    tables = ", ".join(f"{t} {t_['ranges']}" for t, t_ in m["tables"].items() if t_["ranges"])
    print(f"  model ({j['learn_requests']} requests, {j['learn_seconds']:.2f} s): {tables}; "
          f"pauses {m['exception_pause_ms']}; {j['rationed']} cases rationed")
    found = {t: t_["found_during_run"] for t, t_ in m["tables"].items() if t_.get("found_during_run")}
    print(f"  refined during the run: {j.get('refine_requests', 0)} requests, "
          f"{j.get('refine_seconds', 0):.2f} s, every gap asked: {j.get('refine_done', False)}; "
          f"found {found or 'nothing'}")
print(f"  cases by class: {j['cases_by_class']}")
for f in j["findings"]:
    print(f"  #{f['id']:<3} {f['root_cause']:<70} hits {f['hits']:<6} restarts {f['restarts']} "
          f"at {f['found_after_s']:.1f} s")
PY
}

/usr/bin/python3 "$here/peers/pymodbus_server.py" --seconds $((secs + 60)) > "$work/py.port" 2>/dev/null &
fuzz pymodbus "127.0.0.1:$(wait_port "$work/py.port")"
"$build/tests/libmodbus_test_server" --seconds $((secs + 60)) > "$work/lm.port" 2>/dev/null &
fuzz libmodbus "127.0.0.1:$(wait_port "$work/lm.port")"

# libmodbus with a map like its own unit tests' (none at 0): with the model, then without.
for mode in model no-model; do
  flag=(); [ "$mode" = no-model ] && flag=(--no-model)
  "$build/tests/libmodbus_test_server" --seconds $((secs + 60)) --sparse 1 > "$work/lms-$mode.port" 2>/dev/null &
  fuzz "libmodbus-sparse-$mode" "127.0.0.1:$(wait_port "$work/lms-$mode.port")" "${flag[@]}"
done

# The second multi-fault target under its own supervisor (restarts within 20 ms, no
# --restart-cmd): structured, then naive.
for mode in structured naive; do
  flag=(); [ "$mode" = naive ] && flag=(--naive)
  "$build/tests/sparse_device_server" --port 0 --respawn --restart-delay-ms 20 \
    --exit-after-s $((secs + 60)) > "$work/sd-$mode.port" 2>/dev/null &
  fuzz "sparse-device-$mode" "127.0.0.1:$(wait_port "$work/sd-$mode.port")" "${flag[@]}"
done

mf() { echo "$build/tests/multi_fault_server --port $mf_port --exit-after-s $((secs + 60))"; }
for mode in structured naive; do
  flag=(); [ "$mode" = naive ] && flag=(--naive)
  $(mf) > "$work/mf-$mode.port" 2>/dev/null &
  wait_port "$work/mf-$mode.port" > /dev/null
  fuzz "multi-fault-$mode" "127.0.0.1:$mf_port" "${flag[@]}" \
    --restart-cmd "$(mf) </dev/null >/dev/null 2>&1 &"
  pkill -f "multi_fault_server --port $mf_port" 2>/dev/null || true
  sleep 0.5
done
