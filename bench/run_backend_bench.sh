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

# shellcheck source=lib/limit_pair.bash
source "$here/lib/limit_pair.bash"
trap stop_server EXIT

row() {  # row LABEL RUNS_A RUNS_B RUNS_C: medians and the ratios against the first two
  local a b c
  a=$(median <<<"$2"); b=$(median <<<"$3"); c=$(median <<<"$4")
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
    b+="$(mbstorm_client "$mbstorm" io_uring "$c" "$d") "
    e+="$(mbstorm_client "$mbstorm" epoll "$c" "$d") "
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
    start_serve "$mbstorm" io_uring; b+="$(pair_client "$c" "$d") "; stop_server
    start_serve "$mbstorm" epoll; e+="$(pair_client "$c" "$d") "; stop_server
  done
  row "$c x $d" "$a" "$b" "$e"
done
