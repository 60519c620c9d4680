#!/usr/bin/env bash
# mbstorm fuzz --serial (issue #15) against mbstorm serve --serial over a socat pty pair, RTU
# and ASCII: a few seconds of cases (bad CRC/LRC, broken silences, frames without a silence,
# noise before a frame among them) find nothing.
#   bash fuzz_serial.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
source "$scripts/lib/peer.bash"
source "$scripts/lib/serial.bash"
work=$(mktemp -d)
trap 'stop_server; stop_pty_pair; rm -rf "$work"' EXIT

command -v socat >/dev/null || { echo "skip: socat not installed"; exit 77; }
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
ok = (sys.argv[2] == "0" and j["started"] and j["cases"] > 10 and not j["findings"]
      and by.get("bad-checksum", 0) > 0)
print(("ok   " if ok else "FAIL ") + f"{sys.argv[3]}: mbstorm serve --serial: {j['cases']} cases, "
      f"{len(j['findings'])} findings, exit {sys.argv[2]}, classes {by}"
      + "".join(f"\n  {f['root_cause']}: {f['summary']}" for f in j["findings"]))
sys.exit(0 if ok else 1)
PY
  [ "$rc" -le 1 ] || tail -5 "$work/$framing.log"
  stop_server
  stop_pty_pair
done
exit $fail
