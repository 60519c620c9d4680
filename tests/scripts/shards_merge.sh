#!/usr/bin/env bash
# A sharded test run locally exactly as deploy/kubernetes/ runs it: the shard pods' script and
# the merge pod's script, taken from the manifests, run by sh with the environment the Jobs
# give them (JOB_COMPLETION_INDEX, MBSTORM_SHARD_COUNT, TEST_ID, START_AT a few seconds ahead,
# TARGET) against one `mbstorm serve`; the merged result is checked against one process
# running the whole plan: equal transaction totals and error counts (the plan ends by a
# transaction count, so the totals are exact), percentiles alike (loosely: separate runs),
# the shards started together at START_AT, and thresholds give the same verdict (a passing
# set: exit 0 for both; a breached one: exit 1 for both). Also: a late start is reported, bad
# shard values are refused with exit 2, and merge refuses missing and duplicate shards.
#   bash shards_merge.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
deploy=$(cd "$2/../../deploy/kubernetes" && pwd) || { echo "FAIL no deploy/kubernetes"; exit 1; }
work=$(mktemp -d)
pids=()
trap 'for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done; wait 2>/dev/null; rm -rf "$work"' EXIT
cd "$work"
fail=0
ok() { echo "ok   $1"; }
bad() { echo "FAIL $1"; sed 's/^/  err: /' "${2:-err}" 2>/dev/null | tail -5; fail=1; }

# The Jobs' scripts, with the pods' mount points moved into this directory and `mbstorm` on PATH.
mkdir -p bin results etc
ln -s "$mbstorm" bin/mbstorm
export PATH="$work/bin:$PATH"
/usr/bin/python3 - "$deploy" "$work" <<'PY' || { echo "FAIL cannot read the manifests"; exit 1; }
import sys, yaml
deploy, work = sys.argv[1:3]
for job, out in (("shards-job.yaml", "shard.sh"), ("merge-job.yaml", "merge.sh")):
    (doc,) = [d for d in yaml.safe_load_all(open(f"{deploy}/{job}")) if d]
    (c,) = doc["spec"]["template"]["spec"]["containers"]
    assert c["command"] == ["/bin/sh", "-c"], c["command"]
    script = c["args"][0].replace("/results", f"{work}/results").replace("/etc/mbstorm", f"{work}/etc")
    open(f"{work}/{out}", "w").write(script)
PY

source "$(dirname "$0")/lib/peer.bash"
start_mbstorm_serve serve.out "$mbstorm" -d 120s
pids+=("$server_pid")
[ -n "$port" ] || { echo "FAIL mbstorm serve did not start"; cat serve.out.err; exit 1; }

scenario() {  # scenario THRESHOLD...: 6 connections, 3000 transactions after a 1 s warm-up
  printf 'name: fleet\nconnections: 6\ndepth: 2\nduration: 30s\ntransactions: 3000\nwarmup: 1s\n'
  printf 'operations:\n  - {name: read, function: read_holding_registers, address: 0-99, quantity: 10}\n'
  printf 'thresholds:\n'
  for t in "$@"; do printf '  - %s\n' "$t"; done
}
scenario "transactions == 3000" "errors == 0" "p99 < 1h" >etc/scenario.yaml
scenario "transactions > 3000" >breach.yaml

# The shards, as the Indexed Job's pods: same script, same environment, one START_AT.
export MBSTORM_SHARD_COUNT=3 TEST_ID=local-fleet TARGET="127.0.0.1:$port"
start_epoch=$(( $(date +%s) + 4 ))
export START_AT
START_AT=$(date -u -d "@$start_epoch" +%Y-%m-%dT%H:%M:%SZ)
for i in 0 1 2; do
  JOB_COMPLETION_INDEX=$i sh shard.sh >"shard$i.out" 2>"shard$i.err" &
  pids+=($!)
done
# The whole plan in one process (started late on purpose: it reports by how much).
unset MBSTORM_SHARD_COUNT
"$mbstorm" run etc/scenario.yaml --target "$TARGET" --test-id "$TEST_ID" -q --json whole.json --hlog whole.hlog \
  --start-at "$(( $(date +%s) - 3 )).5" >whole.out 2>whole.err
whole_code=$?
"$mbstorm" run breach.yaml --target "$TARGET" -q >breach.out 2>breach.err
breach_code=$?
export MBSTORM_SHARD_COUNT=3
shard_codes=""
for i in 0 1 2; do wait "${pids[$((i + 1))]}"; shard_codes="$shard_codes$?"; done
[ "$shard_codes" = 000 ] && ok "3 shards ran as the Job's pods (exit 0 0 0)" ||
  { bad "shards' exit codes $shard_codes" shard0.err; cat shard1.err shard2.err | tail -5; }

out=results/$TEST_ID
WAIT_SECONDS=20 sh merge.sh >merge.out 2>merge.err
merge_code=$?
if [ "$whole_code" = 0 ] && [ "$merge_code" = 0 ] && grep -q "3 runs of test 'local-fleet'" merge.err; then
  ok "passing thresholds: exit 0 for the whole plan and for the merged shards"
else bad "passing thresholds: whole plan exit $whole_code, merge exit $merge_code" merge.err; fi
"$mbstorm" merge "$out"/shard-*.json "$out"/shard-*.hlog --scenario breach.yaml >mb.out 2>err
merge_breach=$?
[ "$breach_code" = 1 ] && [ "$merge_breach" = 1 ] &&
  ok "a breached threshold: exit 1 for the whole plan and for the merged shards" ||
  bad "breached threshold: whole plan exit $breach_code, merge exit $merge_breach"
grep -q "started [0-9.]*s late (after --start-at): began at once" whole.err &&
  ok "a late start says by how much on the console" || bad "late start message" whole.err

/usr/bin/python3 - whole.json "$out" "$start_epoch" <<'PY' || fail=1
import json, sys
whole = json.load(open(sys.argv[1]))
out, start = sys.argv[2], float(sys.argv[3])
shards = [json.load(open(f"{out}/shard-{i}.json")) for i in range(3)]
merged = json.load(open(f"{out}/merged.json"))
problems = []
def check(what, got, want):
    if got != want: problems.append(f"{what}: {got}, expected {want}")
for key in ("transactions", "transactions_sent", "ok", "errors"):
    check(f"merged totals.{key} vs the whole plan's", merged["totals"][key], whole["totals"][key])
check("merged totals.transactions", merged["totals"]["transactions"], 3000)
check("merged latency.count", merged["latency"]["count"], whole["latency"]["count"])
check("the shards' transactions", [s["totals"]["transactions"] for s in shards], [1000, 1000, 1000])
check("the shards' connections", [s["run"]["connections"] for s in shards], [2, 2, 2])
check("merged connections", merged["run"]["connections"], whole["run"]["connections"])
check("shard numbers", [(s["test"]["shard_index"], s["test"]["shard_count"]) for s in shards],
      [(0, 3), (1, 3), (2, 3)])
# Percentiles: separate runs on a shared machine (CI runs other tests beside this one), so
# only alike; that a merge is exact to the histograms' precision is script.merge_runs' check.
for p in ("50", "90"):
    w, m = whole["latency"]["percentiles_ns"][p], merged["latency"]["percentiles_ns"][p]
    if not (w / 20 <= m <= w * 20):
        problems.append(f"p{p}: merged {m} ns, whole plan {w} ns (more than 20x apart)")
check("merged min_ns", merged["latency"]["min_ns"], min(s["latency"]["min_ns"] for s in shards))
check("merged max_ns", merged["latency"]["max_ns"], max(s["latency"]["max_ns"] for s in shards))
# Together at START_AT: warm-up from there, measuring 1 s later, on every shard.
for s in shards:
    t = s["test"]
    check("start_at_epoch_s", t["start_at_epoch_s"], start)
    check("late_by_seconds", t["late_by_seconds"], 0)
    if abs(t["measure_start_epoch_s"] - (start + 1)) > 0.005:
        problems.append(f"shard {t['shard_index']} measured from {t['measure_start_epoch_s']}, not START_AT + 1 s warm-up ({start + 1})")
late = whole["test"]["late_by_seconds"]
if not 2 <= late <= 10:
    problems.append(f"the whole plan's late_by_seconds {late}, expected about 3")
if problems:
    print("FAIL " + "\nFAIL ".join(problems)); sys.exit(1)
print(f"ok   merged = whole plan: {merged['totals']['transactions']} transactions, {merged['totals']['errors']} errors; "
      f"p50 {merged['latency']['percentiles_ns']['50']} vs {whole['latency']['percentiles_ns']['50']} ns; "
      f"shards measured from START_AT + warm-up; late_by_seconds {late:.2f}")
PY
head -1 "$out/shard-2.hlog" | grep -q "^#\[mbstorm interval log: test local-fleet, run [0-9a-f]*, shard 2/3\]$" &&
  ok "the interval log names its shard" || bad "hlog first line: $(head -1 "$out/shard-2.hlog")"

refused() {  # refused "MESSAGE" COMMAND...
  local want=$1; shift
  "$@" >out 2>err
  if [ $? = 2 ] && grep -q -- "$want" err; then ok "refused: $want"; else bad "$* was not refused with '$want'"; fi
}
refused "missing shards: 2 of 3 given, shard 1 missing" \
  "$mbstorm" merge "$out"/shard-[02].json "$out"/shard-[02].hlog
# Shard 0 twice under another run id (as a pod run twice would leave it).
sed 's/"run_id": *"\([0-9a-f]*\)"/"run_id":"0000000000000dup"/' "$out/shard-0.json" >dup.json
sed '1s/, run [0-9a-f]*,/, run 0000000000000dup,/' "$out/shard-0.hlog" >dup.hlog
refused "duplicate shard 0" "$mbstorm" merge "$out"/shard-*.json "$out"/shard-*.hlog dup.json dup.hlog
refused "is not a shard" "$mbstorm" merge "$out"/shard-*.json "$out"/shard-*.hlog whole.json whole.hlog
refused "JOB_COMPLETION_INDEX=3, MBSTORM_SHARD_COUNT=3: index 3 is out of range for 3 shards" \
  env JOB_COMPLETION_INDEX=3 "$mbstorm" run etc/scenario.yaml --target "$TARGET" -q
refused "MBSTORM_SHARD_COUNT=3 is set but JOB_COMPLETION_INDEX is not" \
  "$mbstorm" run etc/scenario.yaml --target "$TARGET" -q
refused "shard 6/7 gets 0 of the plan's 6 connections" \
  "$mbstorm" run etc/scenario.yaml --target "$TARGET" -q --shard 6/7
refused "is 48.0 h ahead" "$mbstorm" run etc/scenario.yaml --target "$TARGET" -q --shard 0/3 \
  --start-at "$(( $(date +%s) + 172800 ))"
exit $fail
