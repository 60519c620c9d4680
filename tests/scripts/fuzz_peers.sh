#!/usr/bin/env bash
# The fuzzer against servers it did not write, as a user would run it in CI: pymodbus 3.0's
# asyncio server (Debian, /usr/bin/python3) and a libmodbus server. Each run must keep its
# deadline (--seconds + 5 s, restarts and minimisation included) and every finding must be one
# of the deviations these servers really have (triaged by hand: bench/README.md), each once.
# pymodbus closes on a request it cannot decode, whatever its length: that is one root cause
# (close-with-request-pending/invalid-request), never a lost stream besides.
#   bash fuzz_peers.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
bin_dir=$(cd "$(dirname "$mbstorm")" && pwd)
pymodbus_server="$scripts/../../bench/peers/pymodbus_server.py"
libmodbus_server="$bin_dir/tests/libmodbus_test_server"
seconds=15

source "$scripts/lib/peer.bash"
# bounded SECONDS COMMAND...: COMMAND, killed if it outlives SECONDS.
bounded() { timeout -k 5 "$@"; }
work=$(mktemp -d)
trap 'stop_server; rm -rf "$work"' EXIT

fail=0
# fuzz_peer NAME ALLOWED-RULE-STEMS...: fuzzes $port, checks the deadline and the findings.
fuzz_peer() {
  local name=$1; shift
  local t0=$SECONDS
  "$mbstorm" fuzz --target "127.0.0.1:$port" --seconds "$seconds" --seed 1 -q \
    --out "$work/$name" --json "$work/$name.json" >"$work/$name.log" 2>&1
  local rc=$? wall=$((SECONDS - t0))
  if [ "$rc" -ne 0 ] && [ "$rc" -ne 1 ]; then echo "FAIL $name: exit $rc"; sed 's/^/  /' "$work/$name.log" | tail -20; fail=1; return; fi
  if [ "$wall" -gt $((seconds + 5)) ]; then echo "FAIL $name: ran $wall s for --seconds $seconds"; fail=1; fi
  MUST_FIND="${must_find:-}" /usr/bin/python3 - "$work/$name.json" "$@" <<'PY' || fail=1
import json, os, sys
j = json.load(open(sys.argv[1]))
allowed = set(sys.argv[2:])
bad = [f["root_cause"] for f in j["findings"]
       if f["oracle"] + ":" + f["rule"].split("(")[0].split("/")[0] not in allowed]
keys = [f["root_cause"] for f in j["findings"]]
dups = sorted({k for k in keys if keys.count(k) > 1})
missed = [k for k in os.environ["MUST_FIND"].split() if k not in keys]
ok = not bad and not dups and not missed
print(f"{'ok  ' if ok else 'FAIL'} {j['target']}: {len(keys)} root causes in {j['seconds']:.1f} s"
      + (f"; not a known deviation of this server: {bad}" if bad else "")
      + (f"; reported twice: {dups}" if dups else "")
      + (f"; not found: {missed}" if missed else ""))
for k in sorted(keys):
    print(f"       {k}")  # what this run found, for the floors above
sys.exit(0 if ok else 1)
PY
}

if [ -f "$pymodbus_server" ] && /usr/bin/python3 -c 'import pymodbus.server' 2>/dev/null; then
  if start_server "$work/py.out" /usr/bin/python3 "$pymodbus_server" --seconds 120; then
    # The 9 defects of pymodbus 3.0 (bench/README.md, issue #26), named as one finding each:
    # the FC 05 value it never checks is that, not "02 where 03 is owed" (field-level
    # minimisation moves the address into the map), and FC 0F's quantity and byte count are one
    # check. A frame that comes in more than one read it mishandles (its framer closes on a
    # piece of 7 bytes or fewer and throws a longer one away). Read device id code 0 is refused
    # with 04; its file-record handlers are stubs (FC 15 answers a truncated request
    # normally, FC 14's answer has a byte count its data does not match). All 9 came within 6.3 s of a 15-s run
    # of the ASan build beside two CPU hogs (2026-11-29; the first 6 s are learning the map).
    must_find="spec-deviation:answers-nonzero-protocol-id
      unexpected-close:close-with-request-pending/invalid-request
      spec-deviation:invalid-request-answered-normally(owes-03)/fc05
      spec-deviation:invalid-request-answered-normally(owes-03)/fc0F
      spec-deviation:unknown-sub-function-not-refused-with-01
      stream:mishandles-partial-frame spec-deviation:exception-04-where-03-owed
      spec-deviation:invalid-request-answered-normally(owes-03)/fc15
      malformed-response:undecodable-response(byte_count_mismatch)" \
    fuzz_peer pymodbus \
      spec-deviation:answers-nonzero-protocol-id spec-deviation:invalid-request-answered-normally \
      spec-deviation:exception-04-where-01-owed \
      spec-deviation:exception-03-where-01-owed spec-deviation:exception-04-where-03-owed \
      spec-deviation:exception-04-where-02-owed \
      spec-deviation:unknown-sub-function-not-refused-with-01 \
      unexpected-close:close-with-request-pending unexpected-close:closes-on-partial-frame \
      malformed-response:undecodable-response malformed-response:unmatched-transaction-id \
      malformed-response:answers-partial-frame hang:no-answer \
      hang:stream-lost-after-pdu-length-mismatch \
      malformed-response:stream-lost-after-pdu-length-mismatch hang:capacity
    # Every finding replays alone, every time (issue #26), the one saved as a refusal of a
    # frame of the wrong length included (replay understands the target as the run did).
    for folder in "$work"/pymodbus/*/; do
      [ -f "$folder/finding.json" ] || continue
      out=$(bounded 60 "$mbstorm" replay "$folder" --target "127.0.0.1:$port" --runs 2 2>&1)
      if [ $? -eq 1 ] && grep -q "2 of 2 run(s) reproduced" <<<"$out"; then
        echo "ok   replay reproduces $(basename "$folder") 2 of 2"
      else
        echo "FAIL replay of $(basename "$folder")"; sed 's/^/  /' <<<"$out" | tail -5; fail=1
      fi
    done
  else echo "FAIL pymodbus server did not start"; fail=1; fi
  stop_server
else
  echo "pymodbus not available: skipped that peer"
fi

if [ -x "$libmodbus_server" ]; then
  if start_server "$work/lm.out" "$libmodbus_server" --seconds 120; then
    # What every 15-s run found, 3 runs of 3 (2026-11-28 20:58 UTC, quiet machine, each run
    # these three and no more): the protocol id it answers whatever it is, FC 07 it never
    # answers, and a partial frame on one connection that stalls the others (its select()
    # loop waits in modbus_receive for the rest of that frame). The other four of its seven
    # need more than 15 s (bench/README.md: 60-s runs).
    must_find="spec-deviation:answers-nonzero-protocol-id hang:no-answer/fc07
      hang:stalls-other-connections(partial-frame)" \
    fuzz_peer libmodbus \
      spec-deviation:answers-nonzero-protocol-id spec-deviation:exception-02-where-03-owed \
      unexpected-close:close-with-request-pending hang:drops-requests-after-exception \
      hang:drops-requests-after hang:no-answer malformed-response:unmatched-transaction-id \
      unexpected-close:stream-lost-after-pdu-length-mismatch \
      hang:stream-lost-after-pdu-length-mismatch \
      malformed-response:stream-lost-after-pdu-length-mismatch \
      hang:capacity hang:stalls-other-connections
  else echo "FAIL libmodbus server did not start"; fail=1; fi
  stop_server
else
  echo "libmodbus server not built (libmodbus-dev missing): skipped that peer"
fi
exit $fail
