#!/usr/bin/env bash
# A run killed with SIGKILL (no chance to clean up) leaves every interval it completed on
# disk, in both --timeline (one JSON object per line) and --hlog, each file ending on a
# whole line.
#   bash killed_run_keeps_intervals.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
work=$(mktemp -d)
pid=""
trap '[ -n "$pid" ] && kill -9 "$pid" 2>/dev/null; wait 2>/dev/null; rm -rf "$work"' EXIT
"$mbstorm" run -d 60s -c 2 --depth 2 -q --test-id killed \
  --timeline "$work/run.jsonl" --hlog "$work/run.hlog" >"$work/out" 2>"$work/err" &
pid=$!
# Until 3 whole intervals are on disk (bounded: 20 s), then one more second into the next.
for _ in $(seq 200); do
  [ -f "$work/run.jsonl" ] && [ "$(wc -l <"$work/run.jsonl")" -ge 3 ] && break
  kill -0 "$pid" 2>/dev/null || break
  sleep 0.1
done
sleep 1
kill -9 "$pid"
wait "$pid" 2>/dev/null
pid=""
/usr/bin/python3 - "$work/run.jsonl" "$work/run.hlog" <<'PY'
import json, sys
timeline, hlog = sys.argv[1], sys.argv[2]
fail = False
def check(ok, what):
    global fail
    print(("ok   " if ok else "FAIL ") + what)
    fail = fail or not ok
text = open(timeline).read()
lines = text.splitlines()
check(text.endswith("\n"), f"--timeline ends on a whole line ({len(lines)} lines)")
objs = [json.loads(l) for l in lines]
check(len(objs) >= 3, "at least the 3 intervals seen before the kill")
check([o["index"] for o in objs] == list(range(len(objs))), "every interval from 0, in order")
check(all(o["transactions"] > 0 and o["test"] == "killed" for o in objs), "each one counted transactions")
check(len({o["run_id"] for o in objs}) == 1, "one run id")
h = open(hlog).read()
check(h.endswith("\n"), "--hlog ends on a whole line")
untagged = [l for l in h.splitlines() if l and not l.startswith(("#", '"', "Tag="))]
check(len(untagged) >= len(objs) - 1, f"--hlog has the completed intervals too ({len(untagged)} lines)")
sys.exit(1 if fail else 0)
PY
