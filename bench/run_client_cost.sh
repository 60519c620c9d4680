#!/usr/bin/env bash
# Where a client's transactions cost CPU, on both sides, at one shape against limit_server:
# the limit pair's epoll client and `mbstorm run` take turns, and each run prints its
# throughput, the server's and the client's CPU nanoseconds per transaction (the client's
# user share apart) and the server's read() calls per transaction (requests per read).
# Where both cores are saturated, throughput says little about a client; its CPU per
# transaction and what it makes the server do say the rest.
#
#   bench/run_client_cost.sh [build-dir] [connections] [depth] [seconds] [repeats]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-$here/../build/release}
connections=${2:-64}
depth=${3:-16}
secs=${4:-5}
repeats=${5:-5}
mbstorm="$build/mbstorm"
limit="$build/bench/limit_server"
client="$build/bench/pipeline_client"
for f in "$mbstorm" "$limit" "$client"; do
  [ -x "$f" ] || { echo "missing $f: build the release preset first" >&2; exit 1; }
done
ulimit -n 20000 2>/dev/null || true
work=$(mktemp -d)
server_pid=""
cleanup() { [ -n "$server_pid" ] && kill "$server_pid" 2>/dev/null; rm -rf "$work"; }
trap cleanup EXIT

taskset -c 0 "$limit" --seconds 3600 >"$work/server.out" 2>/dev/null &
server_pid=$!
for _ in $(seq 100); do grep -q PORT "$work/server.out" && break; sleep 0.05; done
port=$(awk '/PORT/ {print $2}' "$work/server.out")
[ -n "$port" ] || { echo "limit_server did not start" >&2; exit 1; }

server_cpu_ticks() { awk '{print $14 + $15}' "/proc/$server_pid/stat"; }
server_reads() { awk '/^syscr/ {print $2}' "/proc/$server_pid/io"; }
hz=$(getconf CLK_TCK)

# Runs one client, its user and system CPU seconds into $work/time (bash's time keyword);
# prints its transaction count.
TIMEFORMAT='%U %S'
run_client() {
  if [ "$1" = pair ]; then
    { time taskset -c 1 "$client" --port "$port" --connections "$connections" --depth "$depth" \
      --seconds "$secs" --warmup 0 >"$work/pair.out" 2>/dev/null; } 2>"$work/time"
    echo $(($(sed -n 's/^RESULT tps=\([0-9]*\).*/\1/p' "$work/pair.out") * secs))
  else
    { time taskset -c 1 "$mbstorm" run --target "127.0.0.1:$port" --threads 1 -c "$connections" \
      --depth "$depth" -d "${secs}s" -q --json "$work/run.json" >/dev/null 2>&1; } 2>"$work/time"
    /usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["totals"]["transactions"])' "$work/run.json"
  fi
}

echo "| client | tx/s | server CPU ns/tx | client CPU ns/tx | of which user | server reads/tx |"
echo "|---|---:|---:|---:|---:|---:|"
for _ in $(seq "$repeats"); do
  for who in pair mbstorm; do
    ticks0=$(server_cpu_ticks) reads0=$(server_reads)
    tx=$(run_client "$who")
    ticks1=$(server_cpu_ticks) reads1=$(server_reads)
    read -r user sys <"$work/time"
    awk -v who="$who" -v tx="$tx" -v secs="$secs" -v st=$((ticks1 - ticks0)) -v hz="$hz" \
      -v reads=$((reads1 - reads0)) -v user="$user" -v sys="$sys" 'BEGIN {
        printf "| %s | %d | %d | %d | %d | %.4f |\n", who, tx / secs, st / hz / tx * 1e9,
               (user + sys) / tx * 1e9, user / tx * 1e9, reads / tx }'
  done
done
