#!/usr/bin/env bash
# Two builds of mbstorm side by side on both sides, against the limit pair (issue #30: the
# transport seam must not slow the hot path). FC03 reading 10 registers, one thread each,
# server pinned to core 0 and client to core 1, io_uring and epoll.
#   Engine: pipeline_client, then `mbstorm run` of each build, against limit_server.
#   Slave:  pipeline_client against limit_server and `mbstorm serve` of each build.
# Medians of `repeats` runs; within each repeat the contenders of a row take turns.
#
#   bench/run_seam_bench.sh BEFORE_BUILD AFTER_BUILD [seconds-per-run] [repeats]
#   SHAPES="16:16" BACKENDS=io_uring bench/run_seam_bench.sh ...   a subset
set -euo pipefail
before=${1:?usage: run_seam_bench.sh BEFORE_BUILD AFTER_BUILD [seconds] [repeats]}
after=${2:?usage: run_seam_bench.sh BEFORE_BUILD AFTER_BUILD [seconds] [repeats]}
secs=${3:-3}
repeats=${4:-5}
limit="$after/bench/limit_server"
client="$after/bench/pipeline_client"
for f in "$before/mbstorm" "$after/mbstorm" "$limit" "$client"; do
  [ -x "$f" ] || { echo "missing $f: build the release preset first" >&2; exit 1; }
done
ulimit -n 20000 2>/dev/null || true
json=$(mktemp)
server_pid=""
stop_server() { [ -n "$server_pid" ] && kill "$server_pid" 2>/dev/null && wait "$server_pid" 2>/dev/null; server_pid=""; }
trap 'stop_server; rm -f "$json"' EXIT
median() { tr ' ' '\n' | grep -v '^$' | sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }

start_limit() {
  local out; out=$(mktemp)
  taskset -c 0 "$limit" --seconds 3600 >"$out" 2>/dev/null & server_pid=$!
  for _ in $(seq 100); do grep -q PORT "$out" && break; sleep 0.05; done
  port=$(awk '/PORT/ {print $2}' "$out"); rm -f "$out"
}
start_serve() {  # start_serve BUILD BACKEND
  port=$((20000 + RANDOM % 20000))
  taskset -c 0 "$1/mbstorm" serve --backend "$2" --listen "127.0.0.1:$port" --threads 1 \
    --max-connections 0 >/dev/null 2>&1 & server_pid=$!
  sleep 0.5
}
pair_client() {  # pair_client CONNECTIONS DEPTH
  taskset -c 1 "$client" --port "$port" --connections "$1" --depth "$2" --seconds "$secs" \
    --warmup 1 2>/dev/null | sed -n 's/^RESULT tps=\([0-9]*\).*/\1/p'
}
mbstorm_client() {  # mbstorm_client BUILD BACKEND CONNECTIONS DEPTH
  taskset -c 1 "$1/mbstorm" run --backend "$2" --target "127.0.0.1:$port" --threads 1 -c "$3" \
    --depth "$4" -d "${secs}s" --warmup 1s -q --json "$json" >/dev/null 2>&1
  /usr/bin/python3 -c 'import json,sys;print(round(json.load(open(sys.argv[1]))["totals"]["throughput_per_s"]))' "$json"
}
row() {  # row LABEL RUNS_LIMIT RUNS_BEFORE RUNS_AFTER
  local a b c
  a=$(median <<<"$2"); b=$(median <<<"$3"); c=$(median <<<"$4")
  printf '| %s | %s | %s | %s | %.2fx | %.2fx | %.3fx |\n' "$1" "$a" "$b" "$c" \
    "$(echo "$b / $a" | bc -l)" "$(echo "$c / $a" | bc -l)" "$(echo "$c / $b" | bc -l)"
}

shapes=${SHAPES-16:16 64:16}
backends=${BACKENDS-io_uring epoll}
echo "| side, backend, shape | limit pair | before | after | before / limit | after / limit | after / before |"
echo "|---|---:|---:|---:|---:|---:|---:|"
for backend in $backends; do
  for shape in $shapes; do
    c=${shape%:*}; d=${shape#*:}
    start_limit
    a="" b="" e=""
    for _ in $(seq "$repeats"); do
      a+="$(pair_client "$c" "$d") "
      b+="$(mbstorm_client "$before" "$backend" "$c" "$d") "
      e+="$(mbstorm_client "$after" "$backend" "$c" "$d") "
    done
    stop_server
    row "engine, $backend, $c x $d" "$a" "$b" "$e"
  done
  for shape in $shapes; do
    c=${shape%:*}; d=${shape#*:}
    a="" b="" e=""
    for _ in $(seq "$repeats"); do
      start_limit; a+="$(pair_client "$c" "$d") "; stop_server
      start_serve "$before" "$backend"; b+="$(pair_client "$c" "$d") "; stop_server
      start_serve "$after" "$backend"; e+="$(pair_client "$c" "$d") "; stop_server
    done
    row "slave, $backend, $c x $d" "$a" "$b" "$e"
  done
done
