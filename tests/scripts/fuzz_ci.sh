#!/usr/bin/env bash
# The fuzzer in a CI job (issue #29): a target started just before mbstorm is waited for with
# --wait-for-target (the first connect retried), and a target that never comes is an error
# saying how long it was waited for. Known findings are --baseline's part
# (tests/netfuzz/broken_targets_test.cpp, Baseline.*).
#   bash fuzz_ci.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
work=$(mktemp -d)
serve_pid=""
trap '[ -n "$serve_pid" ] && kill "$serve_pid" 2>/dev/null; rm -rf "$work"' EXIT
# bounded SECONDS COMMAND...: COMMAND, killed if it outlives SECONDS.
bounded() { timeout -k 5 "$@"; }
fail=0
port=$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
target=(--target "127.0.0.1:$port" --seconds 2 --seed 3 -q --out "$work/findings")

# Nothing listens: without a wait the run ends at once, exit 2.
bounded 20 "$mbstorm" fuzz "${target[@]}" > "$work/none.log" 2>&1
rc=$?
if [ $rc -ne 2 ]; then echo "FAIL: no target and no wait: exit $rc (2 owed)"; cat "$work/none.log"; fail=1; fi

# A short wait for a target that never comes: exit 2, naming the wait.
bounded 20 "$mbstorm" fuzz "${target[@]}" --wait-for-target 300ms > "$work/short.log" 2>&1
rc=$?
if [ $rc -ne 2 ] || ! grep -q "did not accept a connection within 0.3 s (--wait-for-target)" "$work/short.log"; then
  echo "FAIL: --wait-for-target 300ms with no target: exit $rc"; cat "$work/short.log"; fail=1
fi

# A target that starts a second after mbstorm: waited for, then fuzzed (the reference slave is
# clean: exit 0).
( sleep 1; exec "$mbstorm" serve --listen "127.0.0.1:$port" --duration 60s ) > "$work/serve.out" 2>&1 &
serve_pid=$!
bounded 60 "$mbstorm" fuzz "${target[@]}" --wait-for-target 20s --json "$work/late.json" > "$work/late.log" 2>&1
rc=$?
/usr/bin/python3 - "$work/late.json" "$rc" <<'PY' || { cat "$work/late.log"; fail=1; }
import json, sys
j = json.load(open(sys.argv[1]))
ok = sys.argv[2] == "0" and j["started"] and j["cases"] > 0 and not j["findings"]
print(("ok   " if ok else "FAIL ") + f"a target up 1 s after mbstorm: exit {sys.argv[2]}, "
      f"{j['cases']} cases, {len(j['findings'])} findings")
sys.exit(0 if ok else 1)
PY
[ $fail -eq 0 ] && echo "fuzz_ci: ok"
exit $fail
