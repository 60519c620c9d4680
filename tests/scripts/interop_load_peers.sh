#!/usr/bin/env bash
# Interop: `mbstorm run` against Modbus servers it did not write, the way a user points it at
# a simulator: pymodbus 3.0's asyncio server (Debian, /usr/bin/python3) with every function
# code the engine generates, pipelined; and a libmodbus server (libmodbus's select() loop)
# with the function codes libmodbus implements (all but 0x07, which it leaves unanswered),
# plus one it does not (answered with exception 01, which the engine must count as such, not
# as a malformed answer).
#   bash interop_load_peers.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
bin_dir=$(cd "$(dirname "$mbstorm")" && pwd)
pymodbus_server="$scripts/../../bench/peers/pymodbus_server.py"
libmodbus_server="$bin_dir/tests/libmodbus_test_server"

source "$scripts/lib/peer.bash"
work=$(mktemp -d)
trap 'stop_server; rm -rf "$work"' EXIT
# start_peer <command...>: a peer server for at most 120 s; sets $port.
start_peer() { start_server "$work/peer.out" "$@" --seconds 120; }

# json <file> <python expression over d>: prints the value.
json() { /usr/bin/python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print($2)" "$1"; }

# run_scenario <name> <operations yaml> [<run yaml>]: by default a 2 s run, 4 connections x
# depth 4; ok when it exits 0.
run_scenario() {
  local shape=${3:-}
  [ -n "$shape" ] || shape=$(printf 'connections: 4\ndepth: 4\nduration: 2s')
  cat >"$work/$1.yaml" <<YAML
name: $1
target: 127.0.0.1:$port
$shape
operations:
$2
YAML
  "$mbstorm" run "$work/$1.yaml" -q --json "$work/$1.json" >"$work/$1.log" 2>&1
}

reads_and_writes='  - {function: read_coils, address: 0-99, quantity: 20}
  - {function: read_discrete_inputs, address: 0-99, quantity: 9}
  - {function: read_holding_registers, address: 0-99, quantity: 10}
  - {function: read_input_registers, address: 0-99, quantity: 3}
  - {function: write_single_coil, address: 0-99, values: {mode: counter}}
  - {function: write_single_register, address: 0-99, values: {mode: counter, step: 3}}
  - {function: write_multiple_coils, address: 0-99, quantity: 11, values: {mode: random}}
  - {function: write_multiple_registers, address: 0-99, quantity: 4, values: {mode: counter}}
  - {function: mask_write_register, address: 0-99, and_mask: 0x00F0, values: {mode: constant, value: 0x0102}}
  - {function: read_write_multiple_registers, address: 0-99, quantity: 5, write_quantity: 2}
  - {function: report_server_id}'

fail=0
# check <name> <what> <python condition over d>
check() {
  if [ "$(json "$work/$1.json" "$3")" = True ]; then echo "ok   $1: $2"
  else echo "FAIL $1: $2"; sed 's/^/  /' "$work/$1.log" | head -40; fail=1; fi
}

if [ -f "$pymodbus_server" ] && /usr/bin/python3 -c 'import pymodbus' 2>/dev/null; then
  if start_peer /usr/bin/python3 "$pymodbus_server"; then
    run_scenario pymodbus "$reads_and_writes
  - {function: read_exception_status}
  - {function: diagnostics}
  - {function: get_comm_event_counter}
  - {function: get_comm_event_log}
  - {function: read_fifo_queue, address: 0}
  - {function: encapsulated_interface, device_id_code: 1}" || { echo "FAIL pymodbus run exited $?"; fail=1; }
    check pymodbus "17 function codes pipelined, no errors, no stray answers" \
      'd["totals"]["errors"] == 0 and d["totals"]["stray_responses"] == 0 and len(d["operations"]) == 17 and all(o["totals"]["ok"] > 10 for o in d["operations"])'
  else echo "FAIL pymodbus server did not start"; fail=1; fi
  stop_server
else
  echo "pymodbus not available: skipped that peer"
fi

if [ -x "$libmodbus_server" ]; then
  if start_peer "$libmodbus_server"; then
    run_scenario libmodbus "$reads_and_writes" || { echo "FAIL libmodbus run exited $?"; fail=1; }
    check libmodbus "11 function codes pipelined, no errors, no stray answers" \
      'd["totals"]["errors"] == 0 and d["totals"]["stray_responses"] == 0 and len(d["operations"]) == 11 and all(o["totals"]["ok"] > 10 for o in d["operations"])'
    # libmodbus has no FC 0x0B: every answer must be exception 01, decoded as such. (Not 0x18:
    # libmodbus cannot size requests it does not know, so their data bytes desynchronise its
    # stream; and it never answers 0x07 at all.)
    # libmodbus answers an unknown function only after sleeping its response timeout (0.5 s)
    # and flushing the socket, so this runs one request at a time.
    run_scenario libmodbus-unsupported "  - {function: get_comm_event_counter}" \
      $'connections: 1\ndepth: 1\nduration: 0s\ntransactions: 4\ntimeout: 2s'
    check libmodbus-unsupported "an unsupported function code is counted as exception 01" \
      'd["totals"]["transactions"] == 4 and d["outcomes"]["exception"] == d["totals"]["transactions"] and d["exceptions"] == {"0x01": d["totals"]["transactions"]} and d["outcomes"]["malformed"] == 0'
  else echo "FAIL libmodbus server did not start"; fail=1; fi
  stop_server
else
  echo "libmodbus server not built (libmodbus-dev missing): skipped that peer"
fi
exit $fail
