#!/usr/bin/env bash
# What `run --metrics-listen` costs the load engine (results go into bench/README.md).
#
#   bench/run_metrics_cost.sh [build-dir] [seconds-per-run] [repeats]
#
# `mbstorm serve` (1 thread) pinned to core 0; `mbstorm run` (1 thread, closed loop, 16
# connections x depth 16, FC03 x 10) pinned to core 1, once plain and once with
# --metrics-listen and a scraper (curl, also on core 1) fetching /metrics every second. The
# two take turns within each repeat; medians of the throughput the runs' --json report and of
# the run process's CPU time (user + system) per transaction, which a busy machine disturbs
# less than throughput.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-$here/../build/release}
secs=${2:-5}
repeats=${3:-5}
mbstorm="$build/mbstorm"
[ -x "$mbstorm" ] || { echo "missing $mbstorm: build the release preset first" >&2; exit 1; }
work=$(mktemp -d)
server_pid="" scraper_pid=""
cleanup() {
  [ -n "$scraper_pid" ] && kill "$scraper_pid" 2>/dev/null
  [ -n "$server_pid" ] && kill "$server_pid" 2>/dev/null
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT

taskset -c 0 "$mbstorm" serve --listen 127.0.0.1:0 --threads 1 >"$work/serve.out" 2>&1 &
server_pid=$!
for _ in $(seq 100); do grep -q 'listening on' "$work/serve.out" && break; sleep 0.05; done
slave=$(sed -n 's/.*listening on \([0-9.:]*\) .*/\1/p' "$work/serve.out")
median() { sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
# "<tx/s> <CPU ns per transaction>" of a finished run: its JSON and `times`' CPU seconds.
figures() {
  /usr/bin/python3 -c 'import json,sys
t = json.load(open(sys.argv[1]))["totals"]
print(round(t["throughput_per_s"]), round(float(sys.argv[2]) * 1e9 / max(t["transactions"], 1)))' "$1" "$2"
}

one_run() {  # one_run plain|scraped: prints "<tx/s> <CPU ns per transaction>"
  local extra=()
  if [ "$1" = scraped ]; then
    local port; port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
    extra=(--metrics-listen "127.0.0.1:$port")
    (while sleep 1; do taskset -c 1 curl -s -o /dev/null "http://127.0.0.1:$port/metrics" || true; done) &
    scraper_pid=$!
  fi
  local cpu
  cpu=$( { TIMEFORMAT='%U %S'; time taskset -c 1 "$mbstorm" run --target "$slave" --threads 1 -c 16 --depth 16 \
    -d "${secs}s" --warmup 1s -q "${extra[@]}" --json "$work/run.json" >/dev/null 2>&1; } 2>&1 | awk '{print $1 + $2}')
  if [ -n "$scraper_pid" ]; then kill "$scraper_pid" 2>/dev/null; wait "$scraper_pid" 2>/dev/null || true; scraper_pid=""; fi
  figures "$work/run.json" "$cpu"
}

: >"$work/plain"; : >"$work/scraped"
for r in $(seq "$repeats"); do
  one_run plain >>"$work/plain"
  one_run scraped >>"$work/scraped"
  echo "repeat $r: plain $(tail -1 "$work/plain"), scraped every 1 s $(tail -1 "$work/scraped") (tx/s, CPU ns/tx)" >&2
done
plain=$(cut -d' ' -f1 "$work/plain" | median); scraped=$(cut -d' ' -f1 "$work/scraped" | median)
plain_cpu=$(cut -d' ' -f2 "$work/plain" | median); scraped_cpu=$(cut -d' ' -f2 "$work/scraped" | median)
echo "median of $repeats x ${secs}s: plain $plain tx/s, $plain_cpu CPU ns/tx; with --metrics-listen and a scraper $scraped tx/s, $scraped_cpu CPU ns/tx (throughput $(echo "scale=3; $scraped / $plain" | bc)x, CPU per transaction $(echo "scale=3; $scraped_cpu / $plain_cpu" | bc)x)"
