#!/usr/bin/env bash
# Interop: Wireshark's Modbus/TCP dissector (tshark) as an independent judge of the bytes on
# the wire. `mbstorm run` drives every function code it can generate against the reference
# slave while tshark captures loopback; tshark must decode every ADU both ways, match each
# response to its request, and flag nothing as malformed.
#   bash interop_tshark.sh <mbstorm-binary> <scripts-dir>
# Exit 77 (CTest: skipped) when tshark is missing or may not capture here.
set -u
mbstorm=$1
bin_dir=$(cd "$(dirname "$mbstorm")" && pwd)
tool="$bin_dir/tests/mbstorm_test_server"
[ -x "$tool" ] || { echo "missing $tool"; exit 1; }
command -v tshark >/dev/null || { echo "tshark is not installed (scripts/setup.sh installs it): skipped"; exit 77; }

source "$(cd "$(dirname "$0")" && pwd)/lib/peer.bash"
work=$(mktemp -d)
capture_pid=""
cleanup() {
  [ -n "$capture_pid" ] && kill "$capture_pid" 2>/dev/null && wait "$capture_pid" 2>/dev/null
  stop_server
  rm -rf "$work"
}
trap cleanup EXIT

start_server "$work/server.out" "$tool" --threads 1 --seconds 120 || { echo "server did not start"; exit 1; }

# The capture is stopped (SIGINT, which finishes the file) once the run is done, not after a
# fixed time: a busy machine made a 4-s window too short for the same kind of capture in
# rtu_over_tcp_interop.sh. -a duration only bounds it.
timeout 90 tshark -i lo -f "tcp port $port" -a duration:80 -w "$work/capture.pcapng" >"$work/tshark.log" 2>&1 &
capture_pid=$!
for _ in $(seq 100); do
  grep -q "Capturing on" "$work/tshark.log" && break
  kill -0 "$capture_pid" 2>/dev/null || break
  sleep 0.1
done
if ! grep -q "Capturing on" "$work/tshark.log"; then
  echo "tshark cannot capture on lo here (needs root or CAP_NET_RAW): skipped"
  sed 's/^/  /' "$work/tshark.log"
  exit 77
fi
# dumpcap says "Capturing on" before its capture is under way: on a loaded machine the run's
# 340 transactions (a few ms) came and went before it, and nothing was captured (seen once in
# a full -j2 run beside a build). A second's head start still leaves three of the four.
sleep 1

# Every function code the engine generates, in equal shares, on 2 connections x depth 4.
# The FIFO's pointer (its count register) lies outside the written range 0-99: a mask write
# of 0x0102 there made the count 258 and the read exception 03, whenever the two threads'
# operations happened to meet in that order.
cat >"$work/all.yaml" <<YAML
name: tshark-interop
target: 127.0.0.1:$port
connections: 2
depth: 4
duration: 0s
transactions: 340
operations:
  - {function: read_coils, address: 0-99, quantity: 20}
  - {function: read_discrete_inputs, address: 0-99, quantity: 9}
  - {function: read_holding_registers, address: 0-99, quantity: 10}
  - {function: read_input_registers, address: 0-99, quantity: 3}
  - {function: write_single_coil, address: 0-99, values: {mode: counter}}
  - {function: write_single_register, address: 0-99, values: {mode: counter, step: 3}}
  - {function: read_exception_status}
  - {function: diagnostics}
  - {function: get_comm_event_counter}
  - {function: get_comm_event_log}
  - {function: write_multiple_coils, address: 0-99, quantity: 11, values: {mode: random}}
  - {function: write_multiple_registers, address: 0-99, quantity: 4, values: {mode: counter}}
  - {function: report_server_id}
  - {function: mask_write_register, address: 0-99, and_mask: 0x00F0, values: {mode: constant, value: 0x0102}}
  - {function: read_write_multiple_registers, address: 0-99, quantity: 5, write_quantity: 2}
  - {function: read_fifo_queue, address: 1000}
  - {function: encapsulated_interface, device_id_code: 1}
thresholds:
  - errors == 0
YAML
if ! "$mbstorm" run "$work/all.yaml" -q --json "$work/run.json" >"$work/run.log" 2>&1; then
  echo "FAIL mbstorm run"; sed 's/^/  /' "$work/run.log"; exit 1
fi
sleep 0.5  # what is still in flight on lo reaches the capture
pkill -INT -P "$capture_pid" tshark 2>/dev/null || kill -INT "$capture_pid" 2>/dev/null
wait "$capture_pid" 2>/dev/null; capture_pid=""

# The dissector tells query from response by the server port.
decode=(tshark -r "$work/capture.pcapng" -o "mbtcp.tcp.port:$port")
fail=0
sent=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["totals"]["transactions_sent"])' "$work/run.json")
adus=$("${decode[@]}" -Y mbtcp -T fields -e mbtcp.trans_id 2>/dev/null | tr ',' '\n' | grep -c .)
if [ "$adus" = $((2 * sent)) ]; then echo "ok   tshark decoded $adus Modbus/TCP ADUs ($sent requests, $sent responses)"
else echo "FAIL tshark decoded $adus ADUs, expected $((2 * sent))"; fail=1; fi

bad=$("${decode[@]}" -Y '_ws.malformed || _ws.expert.severity >= warning' 2>/dev/null | grep -vc "Running as user")
if [ "$bad" = 0 ]; then echo "ok   no malformed frames and no dissector warnings"
else echo "FAIL $bad frames flagged by tshark:"; "${decode[@]}" -Y '_ws.malformed || _ws.expert.severity >= warning' 2>/dev/null | head -5; fail=1; fi

# Queries and responses per function code (one line per ADU: "query|response fc").
"${decode[@]}" -Y mbtcp -T fields -E occurrence=a -e tcp.dstport -e modbus.func_code 2>/dev/null |
  awk -v p="$port" '{ n = split($2, f, ","); for (i = 1; i <= n; i++) print ($1 == p ? "query" : "response"), f[i] }' |
  sort | uniq -c >"$work/by_fc"
for fc in 1 2 3 4 5 6 7 8 11 12 15 16 17 22 23 24 43; do
  q=$(awk -v f="$fc" '$2 == "query" && $3 == f {print $1}' "$work/by_fc")
  r=$(awk -v f="$fc" '$2 == "response" && $3 == f {print $1}' "$work/by_fc")
  if [ -n "$q" ] && [ "$q" = "$r" ]; then :; else echo "FAIL fc $fc: ${q:-0} queries, ${r:-0} responses"; fail=1; fi
done
[ $fail = 0 ] && echo "ok   every one of the 17 function codes: as many responses as queries"

# Every response must point back at the frame of its request (the dissector's matching).
unmatched=$("${decode[@]}" -Y "mbtcp && tcp.srcport == $port && !modbus.request_frame" 2>/dev/null | grep -vc "Running as user")
if [ "$unmatched" = 0 ]; then echo "ok   tshark matched every response to its request"
else echo "FAIL $unmatched responses tshark could not match to a request"; fail=1; fi
exit $fail
