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
here=$(cd "$(dirname "$0")" && pwd)
# shellcheck source=lib/limit_pair.bash
source "$here/lib/limit_pair.bash"
trap stop_server EXIT

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
      b+="$(mbstorm_client "$before/mbstorm" "$backend" "$c" "$d") "
      e+="$(mbstorm_client "$after/mbstorm" "$backend" "$c" "$d") "
    done
    stop_server
    row "engine, $backend, $c x $d" "$a" "$b" "$e"
  done
  for shape in $shapes; do
    c=${shape%:*}; d=${shape#*:}
    a="" b="" e=""
    for _ in $(seq "$repeats"); do
      start_limit; a+="$(pair_client "$c" "$d") "; stop_server
      start_serve "$before/mbstorm" "$backend"; b+="$(pair_client "$c" "$d") "; stop_server
      start_serve "$after/mbstorm" "$backend"; e+="$(pair_client "$c" "$d") "; stop_server
    done
    row "slave, $backend, $c x $d" "$a" "$b" "$e"
  done
done
