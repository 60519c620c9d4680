#!/usr/bin/env bash
# `mbstorm read` / `write --serial` against `mbstorm serve --serial` over a socat pty pair, in
# RTU and in ASCII: values round-trip, an exception is named, a silent unit times out, a
# broadcast write is executed unanswered, and writes to a real tty need --allow-writes.
#   bash serial_read_write.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
source "$scripts/lib/peer.bash"
source "$scripts/lib/serial.bash"
serial_prologue

# A device with 100 holding registers: reads past them answer exception 02.
printf 'tables: {holding_registers: 100}\n' >"$work/device.yaml"
fail=0
# expect <name> <wanted exit code> <wanted text> <mbstorm args...>
expect() {
  local name=$1 code=$2 text=$3; shift 3
  local out rc
  out=$(timeout -k 5 20 "$mbstorm" "$@" 2>&1); rc=$?
  if [ "$rc" = "$code" ] && [[ "$out" == *"$text"* ]]; then echo "ok   $name"
  else echo "FAIL $name: exit $rc, wanted $code and '$text'"; sed 's/^/  /' <<<"$out"; fail=1; fi
}

for framing in rtu ascii; do
  rm -f "$work/line_a" "$work/line_b"
  start_pty_pair "$work" || { echo "FAIL: socat made no pty pair"; exit 1; }
  line=(--serial "$work/line_b" --framing "$framing" --baud 38400 --parity none --stop-bits 2)
  start_serial_serve "$work/serve.out" "$mbstorm" "$work/line_a" --framing "$framing" \
    --baud 38400 --parity none --stop-bits 2 --only-unit 3 --device "$work/device.yaml" ||
    { echo "FAIL: serve --serial did not start"; cat "$work/serve.out.err"; exit 1; }
  expect "$framing: f32 written" 0 "wrote 2 register(s)" write "${line[@]}" -u 3 --addr 40011 --type f32 2.5
  expect "$framing: f32 read back" 0 "[10]: 2.5" read "${line[@]}" -u 3 --addr 40011 --type f32
  expect "$framing: json names the tty" 0 "\"target\":\"$work/line_b\"" read "${line[@]}" -u 3 --addr 10 --json
  expect "$framing: exception named" 1 "ILLEGAL DATA ADDRESS" read "${line[@]}" -u 3 --addr 200
  expect "$framing: other unit is silent" 1 "no answer within 300 ms" read "${line[@]}" -u 4 --timeout 300ms
  expect "$framing: broadcast write" 0 "wrote 1 register(s)" write "${line[@]}" -u 0 --addr 20 77
  expect "$framing: broadcast executed" 0 "[20]: 77" read "${line[@]}" -u 3 --addr 20
  expect "$framing: --target excluded" 2 "exclude each other" read "${line[@]}" --target 127.0.0.1
  stop_server
  summary=$(grep '^serial:' "$work/serve.out")
  echo "  server: $summary"
  [[ "$summary" == "serial: 6 requests, 5 responses (1 exceptions), 1 broadcasts, 1 not addressed"* ]] ||
    { echo "FAIL $framing: the server's counts"; fail=1; }
  stop_pty_pair
done

# A tty that is not a pseudo-terminal is a real bus: writing needs --allow-writes. /dev/tty is
# a terminal device outside /dev/pts whether or not one is attached.
expect "real tty needs --allow-writes" 2 "needs --allow-writes" write --serial /dev/tty --addr 1 5
exit $fail
