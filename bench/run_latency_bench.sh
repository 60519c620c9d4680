#!/usr/bin/env bash
# Latency at equal offered load: `mbstorm serve` (io_uring, 1 thread) against the libmodbus
# server (bench/peers/libmodbus_server.c, select loop). Both servers get the same open-loop
# load from `mbstorm run` (FC03 reading 10 registers, 16 connections, one engine thread), whose
# latencies are measured from each transaction's intended send time, so queueing inside a
# server that falls behind shows up (coordinated omission corrected). Server pinned to core 0,
# client to core 1. The question: is mbstorm's p99 no worse than libmodbus's at the same rate?
#
#   bench/run_latency_bench.sh [build-dir] [seconds-per-run] [repeats] [rate ...]
#   WARMUP=1s DEPTH=16 CONNECTIONS=16 bench/run_latency_bench.sh build/release 10 5
#
# Without rates, libmodbus's saturation is found first with a short closed-loop run
# (CONNECTIONS x depth 1) and the rates are 25/50/75 % of it: loads both servers can sustain.
# Each run starts a fresh server; the two servers alternate within each repeat so drift on a
# shared machine hits both alike. The table shows medians of `repeats` runs of each percentile,
# in microseconds; a rate marked * was not sustained (under 95 % delivered, or errors) by the
# server in that column, so its latencies are not a like-for-like comparison.
set -u
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-$here/../build/release}
secs=${2:-10}
repeats=${3:-5}
shift $(($# < 3 ? $# : 3))
rates=("$@")
warmup=${WARMUP:-1s}
depth=${DEPTH:-16}
conns=${CONNECTIONS:-16}
mbstorm="$build/mbstorm"
libmodbus="$build/bench/libmodbus_server"
for f in "$mbstorm" "$libmodbus"; do
  [ -x "$f" ] || { echo "missing $f (build the mbstorm and libmodbus_server targets)" >&2; exit 1; }
done
command -v taskset >/dev/null || { echo "needs taskset (util-linux)" >&2; exit 1; }
ulimit -n 20000 2>/dev/null || true

tmp=$(mktemp -d)
server_pid=""
stop_server() {
  if [ -n "$server_pid" ]; then kill "$server_pid" 2>/dev/null; wait "$server_pid" 2>/dev/null; fi
  server_pid=""
}
cleanup() { stop_server; rm -rf "$tmp"; }
trap cleanup EXIT

# start_server <mbstorm|libmodbus>: sets $port (ephemeral, read from the server's output).
start_server() {
  local out="$tmp/server.out"
  : >"$out"
  case "$1" in
    mbstorm) taskset -c 0 "$mbstorm" serve --listen 127.0.0.1:0 --threads 1 --max-connections 0 \
               >"$out" 2>&1 & ;;
    libmodbus) taskset -c 0 "$libmodbus" --seconds 3600 >"$out" 2>/dev/null & ;;
  esac
  server_pid=$!
  port=""
  for _ in $(seq 100); do
    port=$(sed -n -e 's/^PORT \([0-9]*\).*/\1/p' -e 's/.*listening on 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$out" | head -n1)
    [ -n "$port" ] && break
    sleep 0.05
  done
  [ -n "$port" ]
}

# run_client <port> <mbstorm run flags...>: prints "tput errors p50 p99 p99.9" (latencies in ns)
# from the JSON summary, or nothing when the run failed.
run_client() {
  local p=$1; shift
  rm -f "$tmp/run.json"
  timeout $(( ${secs%.*} + 60 )) taskset -c 1 "$mbstorm" run --target "127.0.0.1:$p" --threads 1 \
    -c "$conns" --fc 3 --quantity 10 -d "${secs}s" --warmup "$warmup" -q --json "$tmp/run.json" "$@" \
    >/dev/null 2>&1
  [ -s "$tmp/run.json" ] || return 0
  /usr/bin/python3 - "$tmp/run.json" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
p = d["latency"]["percentiles_ns"]
print(round(d["totals"]["throughput_per_s"]), d["totals"]["errors"], p["50"], p["99"], p["99.9"])
EOF
}

median() { sort -n | awk '{a[NR]=$1} END {if (NR) print a[int((NR+1)/2)]; else print "n/a"}'; }
us() { awk -v v="$1" 'BEGIN{ if (v == "n/a" || v == "") print "n/a"; else printf "%.0f", v/1000 }'; }

if [ ${#rates[@]} -eq 0 ]; then
  start_server libmodbus || { echo "libmodbus_server did not start" >&2; exit 1; }
  sat=$(run_client "$port" --model closed --depth 1 | awk '{print $1}')
  stop_server
  [ -n "$sat" ] && [ "$sat" -gt 0 ] || { echo "saturation run against libmodbus failed" >&2; exit 1; }
  echo "# libmodbus saturation (closed loop, $conns x depth 1): $sat tx/s" >&2
  for pct in 25 50 75; do rates+=("$(awk -v s="$sat" -v p="$pct" 'BEGIN{ printf "%d", int(s*p/100/100)*100 }')"); done
fi

servers="mbstorm libmodbus"
declare -A p50 p99 p999 flag
for rate in "${rates[@]}"; do
  for s in $servers; do : >"$tmp/$s.$rate"; done
  for rep in $(seq "$repeats"); do
    for s in $servers; do
      if ! start_server "$s"; then echo "# $s did not start" >&2; stop_server; continue; fi
      line=$(run_client "$port" --model open --rate "$rate" --depth "$depth")
      stop_server
      echo "# $s rate=$rate run=$rep: ${line:-failed} (tput errors p50 p99 p99.9 ns)" >&2
      [ -n "$line" ] && echo "$line" >>"$tmp/$s.$rate"
    done
  done
  for s in $servers; do
    f="$tmp/$s.$rate"
    p50[$s,$rate]=$(us "$(awk '{print $3}' "$f" | median)")
    p99[$s,$rate]=$(awk '{print $4}' "$f" | median)
    p999[$s,$rate]=$(us "$(awk '{print $5}' "$f" | median)")
    # Not sustained: any run delivered under 95 % of the offered rate or had errors.
    flag[$s,$rate]=$(awk -v r="$rate" '$1 < 0.95*r || $2 > 0 {bad=1} END {print (bad || NR == 0) ? "*" : ""}' "$f")
  done
done

echo
echo "Open loop, FC03 x10, $conns connections, ${secs}s runs after ${warmup} warm-up, median of $repeats; latencies in us"
echo
echo "| rate (tx/s) | mbstorm p50 / p99 / p99.9 | libmodbus p50 / p99 / p99.9 | p99 ratio (mbstorm / libmodbus) |"
echo "|---:|---:|---:|---:|"
for rate in "${rates[@]}"; do
  ratio=$(awk -v a="${p99[mbstorm,$rate]}" -v b="${p99[libmodbus,$rate]}" \
          'BEGIN{ if (a+0 > 0 && b+0 > 0) printf "%.2f", a/b; else print "n/a" }')
  printf '| %s | %s / %s / %s%s | %s / %s / %s%s | %s |\n' "$rate" \
    "${p50[mbstorm,$rate]}" "$(us "${p99[mbstorm,$rate]}")" "${p999[mbstorm,$rate]}" "${flag[mbstorm,$rate]}" \
    "${p50[libmodbus,$rate]}" "$(us "${p99[libmodbus,$rate]}")" "${p999[libmodbus,$rate]}" "${flag[libmodbus,$rate]}" \
    "$ratio"
done
echo
echo "p99 ratio <= 1.00 means mbstorm's p99 is no worse than libmodbus's at that rate (* = rate not sustained)."
