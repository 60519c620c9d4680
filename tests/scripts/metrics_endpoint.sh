#!/usr/bin/env bash
# run --metrics-listen and serve --metrics-listen serve /metrics (Prometheus text format 0.0.4)
# while they run, on a port they print when given port 0; other paths are 404; run's final
# totals are the --json report's; with --metrics-linger the run's endpoint outlives the run
# until a scrape has taken its final values.
#   bash metrics_endpoint.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
work=$(mktemp -d)
serve_pid="" run_pid=""
trap '[ -n "$run_pid" ] && kill "$run_pid" 2>/dev/null; [ -n "$serve_pid" ] && kill "$serve_pid" 2>/dev/null; wait; rm -rf "$work"' EXIT
fail=0
check() { if eval "$2"; then echo "ok   $1"; else echo "FAIL $1"; fail=1; fi; }

# wait_for (tests/scripts/lib/peer.bash): the first match of a sed expression, up to 10 s.
source "$(dirname "$0")/lib/peer.bash"
# sample FILE NAME{LABELS}: the value of one sample line.
sample() { awk -v key="$2" 'index($0, key " ") == 1 { print $2 }' "$1"; }

"$mbstorm" serve --listen 127.0.0.1:0 --threads 1 -d 25s --metrics-listen 127.0.0.1:0 \
  >"$work/serve.out" 2>"$work/serve.err" &
serve_pid=$!
wait_for 's/.*metrics on \(http:[^ ]*\).*/\1/p' "$work/serve.err" || { echo "FAIL serve printed no metrics URL"; cat "$work/serve.err"; exit 1; }
serve_url=$found
wait_for 's/.*listening on \([0-9.:]*\) .*/\1/p' "$work/serve.out" || { echo "FAIL serve did not listen"; exit 1; }
slave=$found

"$mbstorm" run --target "$slave" -d 3s -R 2000 -c 2 --depth 2 -q --test-id endpoint \
  --metrics-listen 127.0.0.1:0 --json "$work/run.json" >"$work/run.out" 2>"$work/run.err" &
run_pid=$!
wait_for 's/.*metrics on \(http:[^ ]*\).*/\1/p' "$work/run.err" || { echo "FAIL run printed no metrics URL"; cat "$work/run.err"; exit 1; }
run_url=$found; echo "     run: $run_url"
sleep 1.5
curl -sS -D "$work/headers" -o "$work/run1.prom" "$run_url"
check "run's /metrics is text format 0.0.4" "grep -qi '^content-type: text/plain; version=0.0.4' '$work/headers'"
check "run says it is running" "[ \"\$(sample '$work/run1.prom' 'mbstorm_running{test=\"endpoint\"}')\" = 1 ]"
ok_key='mbstorm_transactions_total{test="endpoint",operation="read_holding_registers",function="read_holding_registers",unit="1",outcome="ok"}'
first=$(sample "$work/run1.prom" "$ok_key")
check "transactions are counted while the run goes ($first)" "[ -n '$first' ] && [ '$first' -gt 0 ]"
check "open connections are a gauge of 2" "[ \"\$(sample '$work/run1.prom' 'mbstorm_open_connections{test=\"endpoint\"}')\" = 2 ]"
check "the target rate is exported" "[ \"\$(sample '$work/run1.prom' 'mbstorm_target_transactions_per_second{test=\"endpoint\"}')\" = 2000 ]"
check "latency is a histogram with +Inf" "grep -q '^mbstorm_transaction_latency_seconds_bucket{.*le=\"+Inf\"} [0-9]' '$work/run1.prom'"
code=$(curl -s -o /dev/null -w '%{http_code}' "${run_url%/metrics}/")
check "other paths are 404 ($code)" "[ '$code' = 404 ]"
wait "$run_pid"; run_code=$?; run_pid=""
check "run exits 0 ($run_code)" "[ '$run_code' = 0 ]"
json_total=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["totals"]["transactions"])' "$work/run.json")
check "the run's endpoint is gone with it" "! curl -s -o /dev/null '$run_url'"

# --metrics-linger: the endpoint outlives the run until one scrape has taken the final values
# (the running gauge at 0, the totals the --json report's), then the run exits.
"$mbstorm" run --target "$slave" -d 1s -R 500 -c 1 -q --test-id linger --metrics-listen \
  127.0.0.1:0 --metrics-linger 20s --json "$work/linger.json" >"$work/linger.out" \
  2>"$work/linger.err" &
run_pid=$!
wait_for 's/.*final metrics at \(http:[^ ]*\) until scraped.*/\1/p' "$work/linger.err" ||
  { echo "FAIL --metrics-linger kept no endpoint after the run"; cat "$work/linger.err"; exit 1; }
linger_url=$found
check "the run's reports are written before it lingers" "[ -s '$work/linger.json' ]"
curl -sS -o "$work/linger.prom" "$linger_url"
check "after the run, running is 0" "[ \"\$(sample '$work/linger.prom' 'mbstorm_running{test=\"linger\"}')\" = 0 ]"
linger_total=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["totals"]["transactions"])' "$work/linger.json")
linger_ok=$(sample "$work/linger.prom" 'mbstorm_transactions_total{test="linger",operation="read_holding_registers",function="read_holding_registers",unit="1",outcome="ok"}')
check "the lingering totals are the report's ($linger_ok = $linger_total)" "[ '$linger_ok' = '$linger_total' ]"
for _ in $(seq 50); do kill -0 "$run_pid" 2>/dev/null || break; sleep 0.1; done
check "one scrape after the end lets the run exit" "! kill -0 $run_pid 2>/dev/null"
wait "$run_pid"; linger_code=$?; run_pid=""
check "the lingering run exits 0 ($linger_code)" "[ '$linger_code' = 0 ]"

curl -s -o "$work/serve.prom" "$serve_url"
requests=$(sample "$work/serve.prom" 'mbstorm_slave_requests_total{function="read_holding_registers"}')
check "serve counted the run's requests by function ($requests >= $json_total)" "[ -n '$requests' ] && [ '$requests' -ge '$json_total' ]"
check "serve exports open connections" "grep -q '^mbstorm_slave_open_connections [0-9]' '$work/serve.prom'"
check "serve exports malformed input counts" "grep -q '^mbstorm_slave_malformed_input_total{kind=\"bad_length\"} 0' '$work/serve.prom'"
check "serve exports RTU CRC failures" "grep -q '^mbstorm_slave_malformed_input_total{kind=\"bad_crc\"} 0' '$work/serve.prom'"
# Garbage at the slave shows up as malformed input.
/usr/bin/python3 - "$slave" <<'PY'
import socket, sys
host, port = sys.argv[1].rsplit(":", 1)
s = socket.create_connection((host, int(port)), timeout=5)
s.sendall(bytes([0, 1, 0, 0, 0, 0, 1, 3]))  # MBAP length 0
try:
    s.recv(100)
except OSError:
    pass
PY
sleep 0.3
curl -s -o "$work/serve2.prom" "$serve_url"
check "a bad MBAP length is counted" "grep -q '^mbstorm_slave_malformed_input_total{kind=\"bad_length\"} 1' '$work/serve2.prom'"
code=$(curl -s -o /dev/null -w '%{http_code}' -X POST "$serve_url")
check "POST is refused ($code)" "[ '$code' = 405 ]"
exit $fail
