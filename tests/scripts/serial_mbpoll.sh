#!/usr/bin/env bash
# Interop: Debian's mbpoll as an independent RTU master against `mbstorm serve --serial` over a
# socat pseudo-terminal pair: reads, a write read back, an exception named, and the server's
# count of what it saw.
#   bash serial_mbpoll.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
source "$scripts/lib/peer.bash"
source "$scripts/lib/serial.bash"
serial_prologue
command -v mbpoll >/dev/null || { echo "skip: mbpoll not installed"; exit 77; }
start_pty_pair "$work" || { echo "FAIL: socat made no pty pair"; exit 1; }
start_serial_serve "$work/serve.out" "$mbstorm" "$work/line_a" --baud 19200 --parity even \
  --only-unit 17 || { echo "FAIL: serve --serial did not start"; cat "$work/serve.out.err"; exit 1; }

fail=0
line=$work/line_b
# expect <name> <wanted exit code> <wanted text> <mbpoll args...> (the device, then values)
expect() {
  local name=$1 code=$2 text=$3; shift 3
  local out rc
  out=$(timeout -k 5 20 mbpoll -m rtu -b 19200 -P even -a 17 -1 "$@" 2>&1); rc=$?
  if [ "$rc" = "$code" ] && [[ "$out" == *"$text"* ]]; then echo "ok   $name"
  else echo "FAIL $name: exit $rc, wanted $code and '$text'"; sed 's/^/  /' <<<"$out"; fail=1; fi
}
# mbpoll counts references from 1: -r 3 is address 2.
expect "read 10 holding registers" 0 "[10]: 	0" -r 1 -c 10 "$line"
expect "write one register" 0 "Written 1 references" -r 3 "$line" 4242
expect "write several" 0 "Written 3 references" -r 5 "$line" 7 8 9
expect "read back" 0 $'[3]: \t4242\n[4]: \t0\n[5]: \t7\n[6]: \t8\n[7]: \t9' -r 3 -c 5 "$line"
expect "coils written" 0 "Written 2 references" -t 0 -r 1 "$line" 1 1
expect "coils read back" 0 $'[1]: \t1\n[2]: \t1\n[3]: \t0' -t 0 -r 1 -c 3 "$line"
expect "input registers" 0 "[1]: 	0" -t 3 -r 1 -c 2 "$line"
expect "exception named" 1 "Illegal data address" -r 65530 -c 10 "$line"
stop_server
summary=$(grep '^serial:' "$work/serve.out")
echo "server: $summary"
[[ "$summary" == "serial: 8 requests, 8 responses (1 exceptions)"* ]] || {
  echo "FAIL: the server's counts"; fail=1; }
exit $fail
