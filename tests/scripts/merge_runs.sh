#!/usr/bin/env bash
# `mbstorm merge`: two `mbstorm run` processes against one `mbstorm serve`, started a second
# apart, merged into one report: totals add, the latency histogram is the two runs' added
# (count, min and max exact; percentiles between the runs'), the timeline spans both on the
# wall clock, thresholds are judged on the merged result with run's exit codes; duplicate,
# missing and foreign runs and other histogram settings are refused with exit code 2.
#   bash merge_runs.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
work=$(mktemp -d)
server_pid=""
trap '[ -n "$server_pid" ] && kill "$server_pid" 2>/dev/null; wait 2>/dev/null; rm -rf "$work"' EXIT
cd "$work"
fail=0
ok() { echo "ok   $1"; }
bad() { echo "FAIL $1"; sed 's/^/  err: /' err 2>/dev/null | tail -5; fail=1; }

source "$(dirname "$0")/lib/peer.bash"
start_mbstorm_serve serve.out "$mbstorm" -d 60s || { echo "FAIL mbstorm serve did not start"; cat serve.out.err; exit 1; }

scenario() {  # scenario NAME THRESHOLD...: a 3 s scenario of reads with those thresholds
  printf 'name: %s\nconnections: 2\ndepth: 2\nduration: 3s\noperations:\n' "$1"
  printf '  - {name: read, function: read_holding_registers, address: 0-99, quantity: 10}\n'
  printf 'thresholds:\n'
  shift
  for t in "$@"; do printf '  - %s\n' "$t"; done
}
scenario shard "p99 < 1h" "error_rate < 100%" >shard.yaml
scenario breach "throughput > 1000000000/s" >breach.yaml
run() {  # run NAME TEST-ID SECONDS
  "$mbstorm" run shard.yaml --target "127.0.0.1:$port" -d "$3s" -q --test-id "$2" \
    --json "$1.json" --hlog "$1.hlog" >"$1.out" 2>"$1.err"
}
run a e2e 3 & pid_a=$!
sleep 1
run b e2e 3 & pid_b=$!
run c other 3 & pid_c=$!
wait $pid_a && wait $pid_b && wait $pid_c || { echo "FAIL a run failed"; cat ./*.err | tail; exit 1; }

"$mbstorm" merge a.json a.hlog b.hlog b.json --json m.json --hdr m.hgrm --junit m.xml >out 2>err
code=$?
if [ $code = 0 ] && grep -q "mbstorm merge: 2 runs of test 'e2e', 2 thresholds judged" err &&
   grep -q Throughput out && grep -q 'PASS  p99 < 1h' out; then
  ok "merge of two runs: exit 0, the console report, the runs' thresholds judged on the merged result"
else bad "merge a b (exit $code)"; fi

/usr/bin/python3 - a.json b.json m.json <<'PY' || fail=1
import json, sys
a, b, m = (json.load(open(p)) for p in sys.argv[1:4])
problems = []
def check(what, got, want):
    if got != want: problems.append(f"{what}: merged {got}, expected {want}")
for key in ("transactions", "transactions_sent", "ok", "errors", "bytes_sent", "bytes_received"):
    check(f"totals.{key}", m["totals"][key], a["totals"][key] + b["totals"][key])
for key, value in m["outcomes"].items():
    check(f"outcomes.{key}", value, a["outcomes"][key] + b["outcomes"][key])
check("latency.count", m["latency"]["count"], a["latency"]["count"] + b["latency"]["count"])
check("latency.max_ns", m["latency"]["max_ns"], max(a["latency"]["max_ns"], b["latency"]["max_ns"]))
check("latency.min_ns", m["latency"]["min_ns"], min(a["latency"]["min_ns"], b["latency"]["min_ns"]))
for p in ("50", "90", "99", "99.9"):
    lo = min(a["latency"]["percentiles_ns"][p], b["latency"]["percentiles_ns"][p])
    hi = max(a["latency"]["percentiles_ns"][p], b["latency"]["percentiles_ns"][p])
    if not lo <= m["latency"]["percentiles_ns"][p] <= hi:
        problems.append(f"p{p}: merged {m['latency']['percentiles_ns'][p]} outside the runs' {lo}..{hi}")
check("operations[0].latency.count", m["operations"][0]["latency"]["count"],
      a["operations"][0]["latency"]["count"] + b["operations"][0]["latency"]["count"])
check("test.merged_runs", m["test"]["merged_runs"], 2)
check("run.connections", m["run"]["connections"], 4)
ivs = m["timeline"]["intervals"]
check("timeline transactions", sum(i["transactions"] for i in ivs), m["totals"]["transactions"])
check("timeline latencies", sum(i["latency_count"] for i in ivs), m["latency"]["count"])
# b started about a second after a: the merged timeline spans about 4 s.
if not 3.5 <= m["run"]["measured_duration_s"] <= 6.0 or len(ivs) < 4:
    problems.append(f"timeline: {len(ivs)} intervals over {m['run']['measured_duration_s']} s, expected about 4 s")
if problems:
    print("FAIL " + "\nFAIL ".join(problems)); sys.exit(1)
print(f"ok   merged totals add ({m['totals']['transactions']} transactions), latency count/min/max exact, "
      f"percentiles between the runs', timeline {len(ivs)} intervals on the wall clock")
PY
grep -q '^#\[Max' m.hgrm && grep -q '<testsuite' m.xml && ok "merge writes --hdr and --junit" || bad "merge --hdr/--junit files"

"$mbstorm" merge a.json a.hlog b.json b.hlog --scenario breach.yaml --junit j.xml >out 2>err
[ $? = 1 ] && grep -q '1 of 1 threshold breached' err && grep -q '<failure' j.xml &&
  ok "a threshold breached on the merged result: exit 1, JUnit failure" || bad "merge --scenario breach.yaml"

refused() {  # refused "MESSAGE" ARGS...
  local want=$1; shift
  "$mbstorm" merge "$@" >out 2>err
  if [ $? = 2 ] && grep -q -- "$want" err; then ok "refused ($want)"; else bad "merge $* was not refused with '$want'"; fi
}
refused "duplicate run" a.json a.hlog a.json a.hlog
refused "no interval log of this run given" a.json a.hlog b.json
refused "whose JSON summary is not given" a.json a.hlog b.hlog
refused "is from another test: test id 'other'" a.json a.hlog c.json c.hlog
refused "says the test has 3: missing runs" a.json a.hlog b.json b.hlog --expect 3
/usr/bin/python3 -c '
import json; d = json.load(open("b.json")); d["test"]["histogram"]["significant_digits"] = 2
json.dump(d, open("b2.json", "w"))'
refused "different histogram settings" a.json a.hlog b2.json b.hlog
refused "m.json: not a run's JSON summary mbstorm merge can read: it is a merged result (2 runs)" m.json a.json a.hlog

# Stages: two runs of a staged scenario merge into one per-stage table (each stage's counts
# added, its latencies the runs' stage histograms from their logs' stage lines, added).
cat >staged.yaml <<'YAML'
name: staged
connections: 2
depth: 2
rate: 400
operations:
  - {name: read, function: read_holding_registers, address: 0-99, quantity: 10}
stages:
  - {name: low, duration: 1s, rate: 400, ramp: constant}
  - {name: high, duration: 1s, rate: 800, ramp: constant}
YAML
pids=()
for r in s1 s2; do
  "$mbstorm" run staged.yaml --target "127.0.0.1:$port" -q --test-id staged --json "$r.json" \
    --hlog "$r.hlog" >"$r.out" 2>"$r.err" &
  pids+=($!)
done
wait "${pids[@]}"
"$mbstorm" merge s1.json s1.hlog s2.json s2.hlog --json sm.json >out 2>err
code=$?
/usr/bin/python3 - s1.json s2.json sm.json "$code" <<'PY' || fail=1
import json, sys
a, b, m = (json.load(open(p)) for p in sys.argv[1:4])
problems = [] if sys.argv[4] == "0" else [f"merge exit {sys.argv[4]}"]
if len(m["stages"]) != 2:
    problems.append(f"{len(m['stages'])} merged stages, expected 2")
for i, st in enumerate(m["stages"][:2]):
    for key, got, want in (
            ("totals.transactions", st["totals"]["transactions"],
             a["stages"][i]["totals"]["transactions"] + b["stages"][i]["totals"]["transactions"]),
            ("latency.count", st["latency"]["count"],
             a["stages"][i]["latency"]["count"] + b["stages"][i]["latency"]["count"]),
            ("latency.max_ns", st["latency"]["max_ns"],
             max(a["stages"][i]["latency"]["max_ns"], b["stages"][i]["latency"]["max_ns"])),
            ("target_rate_to_per_s", st["target_rate_to_per_s"],
             a["stages"][i]["target_rate_to_per_s"] + b["stages"][i]["target_rate_to_per_s"])):
        if got != want: problems.append(f"stage {st['name']} {key}: merged {got}, expected {want}")
if m["latency"]["count"] != a["latency"]["count"] + b["latency"]["count"]:
    problems.append("the stage lines were counted as latencies of the whole run")
if problems:
    print("FAIL " + "\nFAIL ".join(problems)); sys.exit(1)
print("ok   staged runs merge into a per-stage table: " + ", ".join(
    f"{st['name']} {st['totals']['transactions']} tx" for st in m["stages"]))
PY
exit $fail
