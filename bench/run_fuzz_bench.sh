#!/usr/bin/env bash
# Fuzzer benchmark: cases/s against the reference slave on loopback, then time-to-find of each
# planted fault (tests/tools/broken_server_*) for the structure-aware generator versus the
# naive random-frame generator (--naive), same seed, same oracles, same time budget.
# Usage: bench/run_fuzz_bench.sh BUILD_DIR [SECONDS_PER_RUN]
set -euo pipefail
build=${1:?build dir}
secs=${2:-20}
mb="$build/mbstorm"
work=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$work"' EXIT

"$mb" serve --listen 127.0.0.1:0 --threads 2 --duration 600s > "$work/serve.log" &
for _ in $(seq 50); do grep -q "listening on" "$work/serve.log" && break; sleep 0.1; done
target=$(sed -n 's/.*listening on \([0-9.:]*\).*/\1/p' "$work/serve.log")
"$mb" fuzz --target "$target" --seconds "$secs" --seed 1 -q --out "$work/ref" --json "$work/ref.json" > /dev/null || true
python3 - "$work/ref.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
print(f"reference slave: {j['cases']} cases in {j['seconds']:.1f} s = {j['cases_per_second']:.0f} cases/s, "
      f"{len(j['findings'])} findings")
PY
kill %1 2>/dev/null || true

printf "%-26s %-12s %-14s %-14s\n" "planted fault" "oracle" "structured" "naive"
for server in crash hang exception tid split protocol lostwrite; do
  "$build/tests/broken_server_$server" --respawn --restart-delay-ms 200 > "$work/$server.port" &
  pid=$!
  for _ in $(seq 50); do grep -q PORT "$work/$server.port" && break; sleep 0.1; done
  port=$(awk '{print $2}' "$work/$server.port")
  for mode in structured naive; do
    flag=""; [ "$mode" = naive ] && flag="--naive"
    "$mb" fuzz --target "127.0.0.1:$port" --seconds "$secs" --seed 1 --timeout 300ms -q $flag \
      --out "$work/$server-$mode" --json "$work/$server-$mode.json" > /dev/null || true
  done
  python3 - "$server" "$work/$server-structured.json" "$work/$server-naive.json" <<'PY'
import json, sys
server = sys.argv[1]
want = {"crash": ("crash", {15}), "hang": ("hang", {43}), "exception": ("spec-deviation", {3, 4}),
        "tid": ("malformed-response", {23}), "split": (("hang", "unexpected-close"), None),
        "protocol": ("spec-deviation", None), "lostwrite": ("spec-deviation", {16})}[server]
def first(path):
    j = json.load(open(path))
    for f in j["findings"]:
        oracles = want[0] if isinstance(want[0], tuple) else (want[0],)
        if f["oracle"] not in oracles: continue
        if want[1] and f["function"] not in want[1]: continue
        if server == "split" and f["class"] != "split": continue
        if server == "protocol" and f["class"] != "protocol-id": continue
        if server == "lostwrite" and not f["class"].startswith("stateful"): continue
        return f"{f['found_after_s']:.2f} s"
    return f"not in {j['seconds']:.0f} s"
print(f"{'broken_server_' + server:<26} {str(want[0]) if not isinstance(want[0], tuple) else 'hang/close':<12} "
      f"{first(sys.argv[2]):<14} {first(sys.argv[3]):<14}")
PY
  kill $pid 2>/dev/null || true
  wait $pid 2>/dev/null || true
done
