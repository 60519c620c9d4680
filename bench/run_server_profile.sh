#!/usr/bin/env bash
# Where a server's CPU goes at one shape (default 64 connections x depth 1): each server pinned
# to core 0 under bench/tools/pipeline_client on core 1, sampled with `perf record -e cpu-clock`
# (a software clock: works on VMs without hardware counters). Prints, per server, the server
# CPU time per transaction and how it splits between userspace, the kernel's TCP send path
# (tcp_sendmsg, which on loopback also runs the peer's receive processing in softirq), the
# receive path (tcp_recvmsg) and the rest (readiness waits, io_uring/epoll/select plumbing).
#
#   bench/run_server_profile.sh [build-dir] [connections] [depth] [seconds]
#   SERVERS="mbstorm libmodbus" ...
# Needs perf and kernel.perf_event_paranoid <= 1 (or root).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-$here/../build/release}
conns=${2:-64}
depth=${3:-1}
secs=${4:-4}
client="$build/bench/pipeline_client"
command -v perf >/dev/null || { echo "perf is not installed" >&2; exit 1; }
work=$(mktemp -d)
source "$here/lib/servers.bash"
trap 'stop_server; rm -rf "$work"' EXIT

# Percent of samples whose call chain passes through symbol $2 (perf's "children" column).
share_of() {
  perf report -i "$1" --children --sort sym --stdio -g none 2>/dev/null |
    awk -v s="$2" '$NF == s && $3 == "[k]" && !found { gsub("%", "", $1); v = $1; found = 1 } END { print found ? v : 0 }'
}
user_share() {
  perf report -i "$1" --no-children --sort dso --stdio -g none 2>/dev/null |
    awk '/%/ && $2 != "[kernel.kallsyms]" { gsub("%", "", $1); sum += $1 } END { printf "%.1f", sum }'
}

echo "| server ($conns x $depth) | tx/s | server CPU µs/tx | userspace | TCP send path | TCP receive path | rest of kernel |"
echo "|---|---:|---:|---:|---:|---:|---:|"
for s in ${SERVERS:-mbstorm limit libmodbus}; do
  start_server "$s" || { echo "| $s | failed to start | | | | | |"; continue; }
  taskset -c 1 "$client" --port "$port" --connections "$conns" --depth "$depth" \
    --seconds "$secs" --warmup 0.5 >"$work/client" 2>/dev/null &
  cpid=$!
  sleep 1
  t0=$(awk '{print $14 + $15}' "/proc/$server_pid/stat"); w0=$(date +%s.%N)
  perf record -q -e cpu-clock -g -p "$server_pid" -o "$work/perf.data" -- sleep $((secs - 2)) >/dev/null 2>&1
  t1=$(awk '{print $14 + $15}' "/proc/$server_pid/stat"); w1=$(date +%s.%N)
  wait "$cpid"
  tps=$(sed -n 's/^RESULT tps=\([0-9]*\).*/\1/p' "$work/client")
  stop_server
  user=$(user_share "$work/perf.data")
  send=$(share_of "$work/perf.data" tcp_sendmsg)
  recv=$(share_of "$work/perf.data" tcp_recvmsg)
  awk -v s="$s" -v tps="$tps" -v ticks=$((t1 - t0)) -v hz="$(getconf CLK_TCK)" -v w0="$w0" -v w1="$w1" \
      -v user="$user" -v send="$send" -v recv="$recv" 'BEGIN {
    cpu = ticks / hz / (w1 - w0);  # server CPU seconds per second while sampled
    printf "| %s | %d | %.2f | %.1f %% | %.1f %% | %.1f %% | %.1f %% |\n", s, tps, cpu * 1e6 / tps,
           user, send, recv, 100 - user - send - recv }'
done
