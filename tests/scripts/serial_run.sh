#!/usr/bin/env bash
# `mbstorm run --serial` against `mbstorm serve --serial` over a socat pty pair, RTU and ASCII:
# the run's JSON report counts transactions and latencies as a TCP run's does, every
# transaction is answered, and the server saw exactly the run's requests. Then a unit nobody
# serves: every transaction times out. Last, a scenario file on the line: two open-loop stages
# at their own rates, thresholds, --timeline and --hlog, as a TCP run has them.
#   bash serial_run.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
source "$scripts/lib/peer.bash"
source "$scripts/lib/serial.bash"
serial_prologue

fail=0
for framing in rtu ascii; do
  rm -f "$work/line_a" "$work/line_b"
  start_pty_pair "$work" || { echo "FAIL: socat made no pty pair"; exit 1; }
  start_serial_serve "$work/serve.out" "$mbstorm" "$work/line_a" --framing "$framing" \
    --baud 115200 --only-unit 1 ||
    { echo "FAIL: serve --serial did not start"; cat "$work/serve.out.err"; exit 1; }
  timeout -k 5 60 "$mbstorm" run --serial "$work/line_b" --framing "$framing" --baud 115200 \
    --fc 3 --addr 0 --quantity 10 --transactions 200 -d 0 --json "$work/$framing.json" \
    >"$work/run.out" 2>&1
  code=$?
  timeout -k 5 60 "$mbstorm" run --serial "$work/line_b" --framing "$framing" --baud 115200 \
    --unit 9 --timeout 50ms --transactions 5 -d 0 --json "$work/silent.json" >>"$work/run.out" 2>&1
  stop_server
  server=$(grep '^serial:' "$work/serve.out")
  /usr/bin/python3 - "$work/$framing.json" "$work/silent.json" "$server" "$code" "$framing" <<'PY' || { fail=1; sed 's/^/  /' "$work/run.out"; }
import json, sys
run, silent, server, code, framing = json.load(open(sys.argv[1])), json.load(open(sys.argv[2])), sys.argv[3], sys.argv[4], sys.argv[5]
problems = []
if code != "0": problems.append(f"run exit {code}")
t = run["totals"]
if t["transactions"] != 200 or t["ok"] != 200: problems.append(f"totals {t}")
if run["latency"]["count"] != 200: problems.append(f"latency count {run['latency']['count']}")
if not server.startswith("serial: 200 requests, 200 responses (0 exceptions)"): problems.append(f"server: {server}")
if silent["outcomes"]["timeout"] != 5: problems.append(f"silent unit: {silent['outcomes']}")
print(("FAIL " if problems else "ok   ") + f"{framing}: 200 transactions, p50 {run['latency']['percentiles_ns']['50'] / 1e3:.0f} us, p99 {run['latency']['percentiles_ns']['99'] / 1e3:.0f} us")
for p in problems: print("  " + p)
sys.exit(1 if problems else 0)
PY
  stop_pty_pair
done

# A scenario written for TCP (4 connections) run on the line: one master, the stages' rates.
cat >"$work/stages.yaml" <<'YAML'
name: serial-stages
connections: 4
rate: 50
timeout: 200ms
stages:
  - {name: slow, duration: 1s, rate: 50, ramp: constant}
  - {name: fast, duration: 1s, rate: 150, ramp: constant}
operations:
  - {function: read_holding_registers, address: 0-9, quantity: 4}
thresholds:
  - timeouts == 0
YAML
rm -f "$work/line_a" "$work/line_b"
start_pty_pair "$work" || { echo "FAIL: socat made no pty pair"; exit 1; }
start_serial_serve "$work/serve.out" "$mbstorm" "$work/line_a" --baud 115200 ||
  { echo "FAIL: serve --serial did not start"; cat "$work/serve.out.err"; exit 1; }
timeout -k 5 60 "$mbstorm" run "$work/stages.yaml" --serial "$work/line_b" --baud 115200 \
  --json "$work/stages.json" --timeline "$work/timeline.jsonl" --hlog "$work/run.hlog" \
  >"$work/run.out" 2>&1
code=$?
stop_server
/usr/bin/python3 - "$work/stages.json" "$work/timeline.jsonl" "$work/run.hlog" "$code" <<'PY' || { fail=1; sed 's/^/  /' "$work/run.out"; }
import json, sys
run = json.load(open(sys.argv[1]))
timeline = [json.loads(l) for l in open(sys.argv[2]) if l.strip()]
hlog = [l for l in open(sys.argv[3]) if l[:1].isdigit()]
problems = []
# A busy machine may fall short of the schedule: the run must then say so (a "rate" shortfall,
# and its "plan carried out" threshold failed: exit 1); any other failure is one. How fast the
# machine is decides nothing here: the pacer never sends more than asked (10% for the stage
# edges), each stage's schedule shows in the timeline, and a stage short of its rate is owned up.
shortfalls = [f for f in run.get("plan_shortfalls", []) if f["what"] == "rate"]
short_only = [t["expression"] for t in run["thresholds"] if not t["passed"]] == ["plan carried out"]
if sys.argv[4] != "0" and not (sys.argv[4] == "1" and short_only and shortfalls):
    problems.append(f"run exit {sys.argv[4]}, shortfalls {run.get('plan_shortfalls')}")
stages = {s["name"]: s["totals"]["transactions"] for s in run["stages"]}
slow, fast = stages.get("slow", 0), stages.get("fast", 0)
if not 0 < slow <= 55 or not 0 < fast <= 165: problems.append(f"stages: {stages}")
# The engine owns up below 95% of the schedule; 90% leaves room for where its window ends.
if slow + fast < 0.9 * 200 and not shortfalls:
    problems.append(f"stages {stages}: short of 200 in all and no rate shortfall reported")
rates = {round(i["target_rate_per_s"]) for i in timeline}
if not {50, 150} <= rates: problems.append(f"scheduled rates in the timeline: {sorted(rates)}")
if sum(i["transactions"] for i in timeline) != run["totals"]["transactions"]:
    problems.append(f"timeline {[i['transactions'] for i in timeline]} vs {run['totals']}")
if len(hlog) < 2: problems.append(f"{len(hlog)} interval lines in the hlog")
if run["thresholds"][0]["passed"] is not True: problems.append(f"thresholds {run['thresholds']}")
print(("FAIL " if problems else "ok   ") + f"scenario on the line: stages {stages}, {len(timeline)} timeline intervals, {len(hlog)} hlog intervals")
for p in problems: print("  " + p)
sys.exit(1 if problems else 0)
PY
exit $fail
