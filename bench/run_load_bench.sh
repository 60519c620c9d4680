#!/usr/bin/env bash
# End-to-end load-engine benchmark (results go into bench/README.md).
#
#   bench/run_load_bench.sh [build-dir] [seconds-per-run] [repeats]
#   SHAPES="" bench/run_load_bench.sh ...   only the no-pipelining row (SHAPES="1:16 64:16": a subset)
#
# Server pinned to core 0, client to core 1, FC03 reading 10 registers, one thread each.
#  1. The physical limit for each shape: bench/tools/pipeline_client against limit_server
#     (both minimal epoll loops), next to `mbstorm run` against the same limit_server.
#  2. Without pipelining (64 connections x depth 1): `mbstorm run` against a libmodbus-style
#     client (64 threads, one blocking connection each), both against `mbstorm serve`.
# Medians of `repeats` runs; the two clients of a row take turns within each repeat.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-$here/../build/release}
secs=${2:-5}
repeats=${3:-3}
mbstorm="$build/mbstorm"
limit="$build/bench/limit_server"
client="$build/bench/pipeline_client"
libmodbus_client="$build/bench/libmodbus_client"
for f in "$mbstorm" "$limit" "$client" "$libmodbus_client"; do
  [ -x "$f" ] || { echo "missing $f: build the release preset first" >&2; exit 1; }
done
ulimit -n 65536 2>/dev/null || ulimit -n 20000 2>/dev/null || true

server_pid=""
stop_server() { [ -n "$server_pid" ] && kill "$server_pid" 2>/dev/null && wait "$server_pid" 2>/dev/null; server_pid=""; }
trap stop_server EXIT

start_limit() {
  local out; out=$(mktemp)
  taskset -c 0 "$limit" --seconds 3600 >"$out" 2>/dev/null & server_pid=$!
  for _ in $(seq 100); do grep -q PORT "$out" && break; sleep 0.05; done
  port=$(awk '/PORT/ {print $2}' "$out")
}
start_mbstorm_serve() {
  port=$((20000 + RANDOM % 20000))
  taskset -c 0 "$mbstorm" serve --listen "127.0.0.1:$port" --threads 1 --max-connections 0 >/dev/null 2>&1 & server_pid=$!
  sleep 0.5
}
median() { sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }

# tx/s of one run of each client.
pair_client() { taskset -c 1 "$client" --port "$port" --connections "$1" --depth "$2" --seconds "$secs" --warmup 1 2>/dev/null | sed -n 's/^RESULT tps=\([0-9]*\).*/\1/p'; }
mbstorm_client() {
  taskset -c 1 "$mbstorm" run --target "127.0.0.1:$port" --threads 1 -c "$1" --depth "$2" -d "${secs}s" --warmup 1s -q \
    --json /tmp/mbstorm-bench.json >/dev/null 2>&1
  /usr/bin/python3 -c 'import json;d=json.load(open("/tmp/mbstorm-bench.json"));print(round(d["totals"]["throughput_per_s"]))'
}
libmodbus() { taskset -c 1 "$libmodbus_client" 127.0.0.1 "$port" "$1" "$secs" | awk '{print $6}'; }

echo "| shape (connections x depth) | limit pair client | mbstorm run | ratio |"
echo "|---|---:|---:|---:|"
for shape in ${SHAPES-1:16 16:16 64:16 1:256}; do
  c=${shape%:*}; d=${shape#*:}
  start_limit
  # The two clients take turns, so this VM's drift from minute to minute hits both alike.
  runs_a="" runs_b=""
  for _ in $(seq "$repeats"); do
    runs_a+="$(pair_client "$c" "$d") "
    runs_b+="$(mbstorm_client "$c" "$d") "
  done
  a=$(tr ' ' '\n' <<<"$runs_a" | grep -v '^$' | median)
  b=$(tr ' ' '\n' <<<"$runs_b" | grep -v '^$' | median)
  stop_server
  printf '| %s x %s | %s | %s | %.2fx |\n' "$c" "$d" "$a" "$b" "$(echo "$b / $a" | bc -l)"
done

echo
echo "| no pipelining, 64 x 1, against mbstorm serve | tx/s |"
echo "|---|---:|"
start_mbstorm_serve
runs_a="" runs_b=""
for _ in $(seq "$repeats"); do
  runs_a+="$(libmodbus 64) "
  runs_b+="$(mbstorm_client 64 1) "
done
a=$(tr ' ' '\n' <<<"$runs_a" | grep -v '^$' | median)
b=$(tr ' ' '\n' <<<"$runs_b" | grep -v '^$' | median)
stop_server
echo "| libmodbus client, 64 threads | $a |"
printf '| mbstorm run, 1 thread | %s (%.2fx) |\n' "$b" "$(echo "$b / $a" | bc -l)"
