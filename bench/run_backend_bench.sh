#!/usr/bin/env bash
# The epoll backend against the io_uring one and the limit pair (results go into
# bench/README.md), both sides, FC03 reading 10 registers, one thread each, server pinned to
# core 0 and client to core 1.
#   Engine: bench/tools/pipeline_client, `mbstorm run --backend io_uring` and
#           `mbstorm run --backend epoll`, each against limit_server.
#   Slave:  pipeline_client against limit_server, `mbstorm serve --backend io_uring` and
#           `mbstorm serve --backend epoll`.
# Medians of `repeats` runs; within each repeat the contenders of a row take turns.
#
#   bench/run_backend_bench.sh [build-dir] [seconds-per-run] [repeats]
#   SHAPES="16:16 64:16" bench/run_backend_bench.sh ...   a subset
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-$here/../build/release}
secs=${2:-3}
repeats=${3:-3}
mbstorm="$build/mbstorm"
limit="$build/bench/limit_server"
client="$build/bench/pipeline_client"
for f in "$mbstorm" "$limit" "$client"; do
  [ -x "$f" ] || { echo "missing $f: build the release preset first" >&2; exit 1; }
done
ulimit -n 20000 2>/dev/null || true

server_pid=""
stop_server() { [ -n "$server_pid" ] && kill "$server_pid" 2>/dev/null && wait "$server_pid" 2>/dev/null; server_pid=""; }
trap stop_server EXIT
median() { sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }

start_limit() {
  local out; out=$(mktemp)
  taskset -c 0 "$limit" --seconds 3600 >"$out" 2>/dev/null & server_pid=$!
  for _ in $(seq 100); do grep -q PORT "$out" && break; sleep 0.05; done
  port=$(awk '/PORT/ {print $2}' "$out"); rm -f "$out"
}
start_serve() {  # start_serve BACKEND
  port=$((20000 + RANDOM % 20000))
  taskset -c 0 "$mbstorm" serve --backend "$1" --listen "127.0.0.1:$port" --threads 1 \
    --max-connections 0 >/dev/null 2>&1 & server_pid=$!
  sleep 0.5
}
pair_client() {  # pair_client CONNECTIONS DEPTH
  taskset -c 1 "$client" --port "$port" --connections "$1" --depth "$2" --seconds "$secs" \
    --warmup 1 2>/dev/null | sed -n 's/^RESULT tps=\([0-9]*\).*/\1/p'
}
mbstorm_client() {  # mbstorm_client BACKEND CONNECTIONS DEPTH
  taskset -c 1 "$mbstorm" run --backend "$1" --target "127.0.0.1:$port" --threads 1 -c "$2" \
    --depth "$3" -d "${secs}s" --warmup 1s -q --json /tmp/mbstorm-backend-bench.json >/dev/null 2>&1
  /usr/bin/python3 -c 'import json;d=json.load(open("/tmp/mbstorm-backend-bench.json"));print(round(d["totals"]["throughput_per_s"]))'
}
row() {  # row LABEL RUNS_A RUNS_B RUNS_C: medians and the ratios against the first two
  local a b c
  a=$(tr ' ' '\n' <<<"$2" | grep -v '^$' | median)
  b=$(tr ' ' '\n' <<<"$3" | grep -v '^$' | median)
  c=$(tr ' ' '\n' <<<"$4" | grep -v '^$' | median)
  printf '| %s | %s | %s | %s | %.2fx | %.2fx |\n' "$1" "$a" "$b" "$c" \
    "$(echo "$c / $b" | bc -l)" "$(echo "$c / $a" | bc -l)"
}

shapes=${SHAPES-1:16 16:16 64:16 64:1 1:256}
echo "Engine (client) side, against limit_server:"
echo
echo "| shape (connections x depth) | limit pair client | run, io_uring | run, epoll | epoll / io_uring | epoll / limit pair |"
echo "|---|---:|---:|---:|---:|---:|"
for shape in $shapes; do
  c=${shape%:*}; d=${shape#*:}
  start_limit
  a="" b="" e=""
  for _ in $(seq "$repeats"); do
    a+="$(pair_client "$c" "$d") "
    b+="$(mbstorm_client io_uring "$c" "$d") "
    e+="$(mbstorm_client epoll "$c" "$d") "
  done
  stop_server
  row "$c x $d" "$a" "$b" "$e"
done

echo
echo "Slave (server) side, pipeline_client against each:"
echo
echo "| shape (connections x depth) | limit_server | serve, io_uring | serve, epoll | epoll / io_uring | epoll / limit_server |"
echo "|---|---:|---:|---:|---:|---:|"
for shape in $shapes; do
  c=${shape%:*}; d=${shape#*:}
  a="" b="" e=""
  for _ in $(seq "$repeats"); do
    start_limit; a+="$(pair_client "$c" "$d") "; stop_server
    start_serve io_uring; b+="$(pair_client "$c" "$d") "; stop_server
    start_serve epoll; e+="$(pair_client "$c" "$d") "; stop_server
  done
  row "$c x $d" "$a" "$b" "$e"
done
