#!/usr/bin/env bash
# Interop: `mbstorm read` and `run --serial` against pymodbus 3.0's asyncio serial server
# (Debian, /usr/bin/python3, needs python3-serial-asyncio) over a socat pty pair, RTU and ASCII:
# the values pymodbus holds come back, and a run's transactions are all answered.
#   bash serial_pymodbus.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
source "$scripts/lib/peer.bash"
source "$scripts/lib/serial.bash"
serial_prologue

/usr/bin/python3 -c 'import pymodbus.server, serial_asyncio' 2>/dev/null ||
  { echo "skip: pymodbus or serial_asyncio not installed"; exit 77; }

fail=0
for framing in rtu ascii; do
  rm -f "$work/line_a" "$work/line_b"
  start_pty_pair "$work" || { echo "FAIL: socat made no pty pair"; exit 1; }
  /usr/bin/python3 "$scripts/pymodbus_serial_server.py" "$work/line_a" "$framing" --seconds 60 \
    >"$work/peer.out" 2>&1 &
  server_pid=$!
  for _ in $(seq 300); do grep -q READY "$work/peer.out" && break; sleep 0.1; done
  grep -q READY "$work/peer.out" ||
    { echo "FAIL $framing: pymodbus did not start in 30 s"; sed 's/^/  /' "$work/peer.out"; exit 1; }
  line=(--serial "$work/line_b" --framing "$framing" --parity none)
  # The Python peer, beside other tests on two cores, may take more than the default second to
  # answer its first request (a clean-clone CI run saw an ASCII read time out at 1000 ms while
  # the 100 transactions after it were all answered): the values are what is checked here.
  out=$(timeout -k 5 20 "$mbstorm" read "${line[@]}" --addr 1 --quantity 3 --timeout 5s 2>&1)
  if [[ "$out" == $'[1]: 1001\n[2]: 1002\n[3]: 1003' ]]; then echo "ok   $framing: read pymodbus's registers"
  else echo "FAIL $framing: read"; sed 's/^/  /' <<<"$out"; fail=1; fi
  out=$(timeout -k 5 60 "$mbstorm" run "${line[@]}" --fc 3 --addr 0 --quantity 5 --transactions 100 \
    -d 0 --timeout 5s 2>&1)
  if grep -q "Throughput.*(100 transactions" <<<"$out" && grep -q "Errors      0 of 100" <<<"$out"; then
    echo "ok   $framing: run --serial, 100 transactions answered"
  else echo "FAIL $framing: run --serial"; sed 's/^/  /' <<<"$out"; fail=1; fi
  stop_server
  stop_pty_pair
done
exit $fail
