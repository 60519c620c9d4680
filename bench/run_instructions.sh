#!/usr/bin/env bash
# Userspace instructions per transaction of `mbstorm serve` and of `mbstorm run` under
# valgrind's callgrind (an instruction count, so independent of machine load). Each side runs
# the other unprofiled; two client runs of N and 2N transactions (C connections x depth D,
# FC03 x 10). The server is counted from after a warm-up run (lazy symbol binding, first
# buffers), so each run's count over its transactions is the figure; the client's start-up is
# cancelled by the difference of its two runs' counts over N.
#
#   bench/run_instructions.sh [build-dir] [N] [connections] [depth] [serve|run|both]
#   KEEP=dir: keep the callgrind.out files there (for callgrind_annotate)
#   BACKEND=epoll|io_uring: the event backend of both sides (default: auto, io_uring here)
# The server's counters are dumped and zeroed with callgrind_control around each client run
# (the server does not exit on SIGINT under valgrind).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-$here/../build/release}
n=${2:-100000}
conns=${3:-16}
depth=${4:-16}
which=${5:-both}
mb="$build/mbstorm"
work=$(mktemp -d)
keep=${KEEP:-}
backend=${BACKEND:-auto}
server_pid=""
cleanup() {
  if [ -n "$server_pid" ]; then kill -9 "$server_pid" 2>/dev/null || true; wait "$server_pid" 2>/dev/null || true; fi
  rm -rf "$work"
}
trap cleanup EXIT

# Total instructions ("summary:" / "totals:" line) of a callgrind output file.
total_of() { awk '/^(summary|totals):/ { print $2; exit }' "$1"; }
free_port() { /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }
wait_port() {
  for _ in $(seq 300); do
    (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null && return 0
    sleep 0.1
  done
  return 1
}
client_run() {  # client_run <port> <transactions> [valgrind prefix...]
  local p=$1 count=$2; shift 2
  "$@" "$mb" run --backend "$backend" --target "127.0.0.1:$p" -c "$conns" --depth "$depth" \
    -n "$count" -d 0 --warmup 0 >/dev/null 2>&1
}

if [ "$which" = serve ] || [ "$which" = both ]; then
  port=$(free_port)
  valgrind --tool=callgrind --callgrind-out-file="$work/serve.%p" \
    "$mb" serve --backend "$backend" --threads 1 --listen "127.0.0.1:$port" >/dev/null \
    2>"$work/serve.log" &
  server_pid=$!
  wait_port "$port"
  client_run "$port" 1000  # connections, first buffers, page faults
  callgrind_control --zerocost "$server_pid" >/dev/null 2>&1
  client_run "$port" "$n"
  callgrind_control --dump=small "$server_pid" >/dev/null 2>&1
  callgrind_control --zerocost "$server_pid" >/dev/null 2>&1
  client_run "$port" $((2 * n))
  callgrind_control --dump=large "$server_pid" >/dev/null 2>&1
  sleep 0.5
  small=("$work"/serve.*.1); large=("$work"/serve.*.2)
  a=$(total_of "${small[0]}"); b=$(total_of "${large[0]}")
  echo "serve: $a instructions for $n transactions ($(( a / n )) each), $b for $((2 * n)) ($(( b / (2 * n) )) each)"
  if [ -n "$keep" ]; then cp "${large[0]}" "$keep/callgrind.serve"; cp "${small[0]}" "$keep/callgrind.serve.small"; fi
  kill -9 "$server_pid"; wait "$server_pid" 2>/dev/null || true; server_pid=""
fi

if [ "$which" = run ] || [ "$which" = both ]; then
  port=$(free_port)
  "$mb" serve --backend "$backend" --threads 1 --listen "127.0.0.1:$port" >/dev/null 2>&1 &
  server_pid=$!
  wait_port "$port"
  client_run "$port" "$n" valgrind --tool=callgrind --callgrind-out-file="$work/run.small"
  client_run "$port" $((2 * n)) valgrind --tool=callgrind --callgrind-out-file="$work/run.large"
  a=$(total_of "$work/run.small"); b=$(total_of "$work/run.large")
  echo "run:   $a instructions for $n transactions, $b for $((2 * n)): $(( (b - a) / n )) per transaction"
  if [ -n "$keep" ]; then cp "$work/run.large" "$keep/callgrind.run"; cp "$work/run.small" "$keep/callgrind.run.small"; fi
  kill "$server_pid"; wait "$server_pid" 2>/dev/null || true; server_pid=""
fi
