#!/usr/bin/env bash
# mbstorm fuzz --serial (issue #15) against mbstorm serve --serial over a socat pty pair, RTU
# and ASCII: a few seconds of cases (bad CRC/LRC, broken silences, frames without a silence,
# noise before a frame among them) find nothing. Then pymodbus 3.0's serial RTU server, an
# independent slave: what the fuzzer finds there is reported, and replay over the line
# reproduces one confirmed finding.
#   bash fuzz_serial.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
source "$scripts/lib/peer.bash"
source "$scripts/lib/serial.bash"
serial_prologue
# bounded SECONDS COMMAND...: COMMAND, killed if it outlives SECONDS.
bounded() { timeout -k 5 "$@"; }

fail=0
for framing in rtu ascii; do
  rm -f "$work/line_a" "$work/line_b"
  start_pty_pair "$work" || { echo "FAIL: socat made no pty pair"; exit 1; }
  line=(--framing "$framing" --baud 115200 --parity none)
  start_serial_serve "$work/serve.out" "$mbstorm" "$work/line_a" "${line[@]}" ||
    { echo "FAIL: serve --serial did not start"; cat "$work/serve.out.err"; exit 1; }
  bounded 30 "$mbstorm" fuzz --serial "$work/line_b" "${line[@]}" --seconds 4 --seed 5 \
    --timeout 300ms -q --out "$work/$framing" --json "$work/$framing.json" >"$work/$framing.log" 2>&1
  rc=$?
  /usr/bin/python3 - "$work/$framing.json" "$rc" "$framing" <<'PY' || fail=1
import json, sys
j = json.load(open(sys.argv[1]))
by = j.get("cases_by_class", {})
# The line's own mutations among them (every case on a line runs alone: tens, not thousands).
# Which of them a few seconds draw varies (36 cases in 4 s on a quiet machine, fewer on a busy
# one): one of the line's classes at least.
line_classes = ("bad-checksum", "broken-silence", "no-silence", "noise")
ok = (sys.argv[2] == "0" and j["started"] and j["cases"] > 10 and not j["findings"]
      and sum(by.get(c, 0) for c in line_classes) > 0)
print(("ok   " if ok else "FAIL ") + f"{sys.argv[3]}: mbstorm serve --serial: {j['cases']} cases, "
      f"{len(j['findings'])} findings, exit {sys.argv[2]}, classes {by}"
      + "".join(f"\n  {f['root_cause']}: {f['summary']}" for f in j["findings"]))
sys.exit(0 if ok else 1)
PY
  [ "$rc" -le 1 ] || tail -5 "$work/$framing.log"
  stop_server
  stop_pty_pair
done

/usr/bin/python3 -c 'import pymodbus.server, serial_asyncio' 2>/dev/null ||
  { echo "pymodbus or serial_asyncio not installed: skipped that peer"; exit $fail; }
rm -f "$work/line_a" "$work/line_b"
start_pty_pair "$work" || { echo "FAIL: socat made no pty pair"; exit 1; }
/usr/bin/python3 "$scripts/pymodbus_serial_server.py" "$work/line_a" rtu --seconds 60 \
  >"$work/peer.out" 2>&1 &
server_pid=$!
for _ in $(seq 100); do grep -q READY "$work/peer.out" && break; sleep 0.1; done
# pymodbus's serial server runs at 19200 baud with no parity (see the peer's header).
line=(--serial "$work/line_b" --framing rtu --baud 19200 --parity none)
bounded 40 "$mbstorm" fuzz "${line[@]}" --seconds 6 --seed 7 --timeout 300ms -q \
  --out "$work/py" --json "$work/py.json" >"$work/py.log" 2>&1
rc=$?
if [ "$rc" -ne 0 ] && [ "$rc" -ne 1 ]; then
  echo "FAIL pymodbus serial: fuzz exit $rc"; tail -20 "$work/py.log" | sed 's/^/  /'; exit 1
fi
folder=$(/usr/bin/python3 - "$work/py.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
print(f"ok   pymodbus serial RTU server: {j['cases']} cases, {len(j['findings'])} root causes",
      file=sys.stderr)
for f in j["findings"]:
    print(f"  {f['root_cause']}: {f['summary']}", file=sys.stderr)
replayable = [f for f in j["findings"] if f["confirmed"] and f["oracle"] != "crash"]
if replayable: print(replayable[0]["folder"])
# pymodbus 3.0's serial server answers what a serial slave must discard (a broadcast, a frame
# broken by a silence): found in every run with these few dozen cases; one missing is a fuzzer
# that no longer judges what comes back over the line.
floor = ["spec-deviation:answers-broadcast", "spec-deviation:answers-broken-frame"]
missed = [k for k in floor if k not in {f["root_cause"] for f in j["findings"]}]
if missed:
    print(f"FAIL pymodbus over the serial line: not found: {missed}", file=sys.stderr)
sys.exit(0 if j["started"] and j["cases"] > 10 and not missed else 1)
PY
) || { echo "FAIL pymodbus serial: the fuzzer did not get going"; fail=1; }
if [ -n "$folder" ]; then
  out=$(bounded 30 "$mbstorm" replay "$folder" "${line[@]}" --runs 2 2>&1)
  if [ $? -eq 1 ]; then echo "ok   replay over the line reproduces $(basename "$folder")"
  else echo "FAIL replay of $(basename "$folder") does not reproduce"; sed 's/^/  /' <<<"$out"; fail=1; fi
fi
stop_server
exit $fail
