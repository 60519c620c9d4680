#!/usr/bin/env bash
# An interrupted `run` or `fuzz` exits 128 + the signal (130 for SIGINT, 143 for SIGTERM), says
# which signal, and still writes every report it was asked for.
#   bash signals.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
bin_dir=$(cd "$(dirname "$mbstorm")" && pwd)
scripts=$(cd "$2" && pwd)
tool="$bin_dir/tests/mbstorm_test_server"
[ -x "$tool" ] || { echo "missing $tool"; exit 1; }
source "$scripts/lib/peer.bash"
work=$(mktemp -d)
pid=""
trap '[ -n "$pid" ] && kill "$pid" 2>/dev/null; stop_server; rm -rf "$work"' EXIT
fail=0
is_json() { /usr/bin/python3 -c 'import json,sys; json.load(open(sys.argv[1]))' "$1" 2>/dev/null; }

# interrupt <signal> <expected exit> <name> <mbstorm args...>: starts mbstorm, signals it after
# 2 s, and checks the exit code, the message and the JSON report in $work/<name>.json.
interrupt() {
  local sig=$1 expected=$2 name=$3; shift 3
  "$mbstorm" "$@" --json "$work/$name.json" >"$work/$name.out" 2>"$work/$name.err" &
  pid=$!
  sleep 2
  kill "-$sig" "$pid"
  wait "$pid"; local code=$?
  pid=""
  if [ "$code" = "$expected" ] && grep -q "interrupted by SIG$sig" "$work/$name.err" && is_json "$work/$name.json"; then
    echo "ok   $name: SIG$sig -> exit $code, says so, JSON written"
  else
    echo "FAIL $name: SIG$sig -> exit $code (expected $expected)"; sed 's/^/  /' "$work/$name.err" | tail -5; fail=1
  fi
}

interrupt INT 130 run-int run -d 60s -c 2 --depth 2 --html "$work/run-int.html"
[ -s "$work/run-int.html" ] || { echo "FAIL run-int: no HTML report"; fail=1; }
grep -q 'interrupted by SIGINT' "$work/run-int.json" || { echo "FAIL run-int: the JSON notes do not say so"; fail=1; }
interrupt TERM 143 run-term run -d 60s -c 2 --depth 2

start_server "$work/server.out" "$tool" --threads 1 --seconds 120 || { echo "FAIL server did not start"; exit 1; }
interrupt TERM 143 fuzz-term fuzz --target "127.0.0.1:$port" -d 60s -q --no-minimize --out "$work/findings"
interrupt INT 130 fuzz-int fuzz --target "127.0.0.1:$port" -d 60s -q --no-minimize --out "$work/findings"
grep -q '"stop_reason": "interrupted by SIGTERM"' "$work/fuzz-term.json" || { echo "FAIL fuzz-term: the JSON's stop_reason does not name the signal"; fail=1; }
exit $fail
