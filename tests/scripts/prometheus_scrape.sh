#!/usr/bin/env bash
# The real thing: Debian's Prometheus scrapes a running `mbstorm run --metrics-listen` and a
# `mbstorm serve --metrics-listen` every second; afterwards a PromQL query through
# Prometheus's HTTP API returns the transaction total the run's --json reports, to within one
# scrape interval of traffic. Bounded (~20 s); everything started here is killed at the end.
#   bash prometheus_scrape.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
command -v prometheus >/dev/null || { echo "skip: prometheus is not installed (scripts/setup.sh)"; exit 77; }
work=$(mktemp -d)
pids=()
trap 'for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done; wait 2>/dev/null; rm -rf "$work"' EXIT
fail=0
check() { if eval "$2"; then echo "ok   $1"; else echo "FAIL $1"; fail=1; fi; }
# wait_for (tests/scripts/lib/peer.bash): the first match of a sed expression, up to 10 s.
source "$(dirname "$0")/lib/peer.bash"
free_port() {
  /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'
}
rate=500
scrape_s=1

"$mbstorm" serve --listen 127.0.0.1:0 --threads 1 -d 40s --metrics-listen 127.0.0.1:0 \
  >"$work/serve.out" 2>"$work/serve.err" &
pids+=($!)
wait_for 's/.*metrics on http:\/\/\([^ /]*\)\/metrics.*/\1/p' "$work/serve.err" || { echo "FAIL serve printed no metrics address"; exit 1; }
serve_metrics=$found
wait_for 's/.*listening on \([0-9.:]*\) .*/\1/p' "$work/serve.out" || { echo "FAIL serve did not listen"; exit 1; }
slave=$found

# The run's metrics port is chosen first, so that Prometheus scrapes it from the start.
run_metrics="127.0.0.1:$(free_port)"
prom_port=$(free_port)
cat >"$work/prometheus.yml" <<YML
global:
  scrape_interval: ${scrape_s}s
  scrape_timeout: 900ms
scrape_configs:
  - job_name: mbstorm_run
    static_configs: [{targets: ['$run_metrics']}]
  - job_name: mbstorm_serve
    static_configs: [{targets: ['$serve_metrics']}]
YML
prometheus --config.file="$work/prometheus.yml" --storage.tsdb.path="$work/data" \
  --web.listen-address="127.0.0.1:$prom_port" >"$work/prometheus.log" 2>&1 &
pids+=($!)
api="http://127.0.0.1:$prom_port"
for _ in $(seq 100); do curl -sf "$api/-/ready" >/dev/null && break; sleep 0.1; done
curl -sf "$api/-/ready" >/dev/null || { echo "FAIL prometheus did not get ready"; tail -5 "$work/prometheus.log"; exit 1; }

"$mbstorm" run --target "$slave" -d 8s -R "$rate" -c 2 --depth 2 -q --test-id promtest \
  --metrics-listen "$run_metrics" --json "$work/run.json" >"$work/run.out" 2>"$work/run.err"
run_code=$?
check "run exits 0 ($run_code)" "[ '$run_code' = 0 ]"
sleep $((scrape_s + 1))  # serve's last scrape after the run

# query PROMQL: the single value of an instant query, or empty.
query() {
  curl -s -G "$api/api/v1/query" --data-urlencode "query=$1" | /usr/bin/python3 -c '
import json, sys
r = json.load(sys.stdin)["data"]["result"]
print(r[0]["value"][1] if len(r) == 1 else "")'
}
json_total=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["totals"]["transactions"])' "$work/run.json")
# The run's series went stale when it ended: its last scraped values, over the last minute.
prom_total=$(query 'sum(max_over_time(mbstorm_transactions_total{job="mbstorm_run",test="promtest"}[1m]))')
echo "     run --json: $json_total transactions; Prometheus: ${prom_total:-nothing}"
check "Prometheus scraped the run's transactions" "[ -n '$prom_total' ]"
prom_total=${prom_total:-0}
check "within one scrape interval of traffic ($json_total - $prom_total <= $((rate * scrape_s)))" \
  "[ \$(( $json_total - ${prom_total%.*} )) -ge 0 ] && [ \$(( $json_total - ${prom_total%.*} )) -le $((rate * scrape_s)) ]"
ok_rate=$(query 'max(max_over_time(mbstorm_achieved_transactions_per_second{job="mbstorm_run"}[1m]))')
check "the achieved rate gauge reached the target ($ok_rate)" "/usr/bin/python3 -c 'import sys; sys.exit(0 if float(\"${ok_rate:-0}\") >= $rate * 0.9 else 1)'"
buckets=$(query 'sum(max_over_time(mbstorm_transaction_latency_seconds_bucket{job="mbstorm_run",le="+Inf"}[1m]))')
count=$(query 'sum(max_over_time(mbstorm_transaction_latency_seconds_count{job="mbstorm_run"}[1m]))')
check "the latency histogram's +Inf bucket equals its count ($buckets = $count)" "[ -n '$count' ] && [ '$buckets' = '$count' ]"
p99=$(query 'histogram_quantile(0.99, sum by (le) (max_over_time(mbstorm_transaction_latency_seconds_bucket{job="mbstorm_run"}[1m])))')
check "histogram_quantile works on the buckets ($p99 s)" "/usr/bin/python3 -c 'import sys; sys.exit(0 if 0 < float(\"${p99:-0}\") < 1 else 1)'"
served=$(query 'sum(mbstorm_slave_requests_total{job="mbstorm_serve"})')
check "Prometheus scraped serve's requests (${served:-nothing} >= $json_total)" "[ -n '$served' ] && [ '${served%.*}' -ge '$json_total' ]"
up=$(query 'sum(max_over_time(up{job=~"mbstorm_.*"}[30s]))')
check "both targets were up" "[ '$up' = 2 ]"
[ $fail = 0 ] || tail -5 "$work/prometheus.log"
exit $fail
