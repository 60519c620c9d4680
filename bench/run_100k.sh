#!/usr/bin/env bash
# 100,000 connections on one machine (results go into bench/README.md, "100k connections").
#
#   bench/run_100k.sh [build-dir] [connections] [seconds] [source-addresses]
#
# `mbstorm serve` and `mbstorm run` on loopback, the client's connections spread over several
# 127.0.0.0/8 source addresses (each has its own ephemeral ports), a low open-loop rate so that
# the run is about holding connections. Both sides hold their sockets as io_uring direct
# descriptors, so the open-files limit (20,000 here) caps each ring's table, not the total.
# Prints: time to open every connection (connect rate), peak RSS of both sides, the client's
# memory per connection (peak RSS minus that of a 1-connection run with the same settings,
# divided by the connections), the kernel's TCP socket memory and conntrack entries, and the
# run's JSON totals (errors, p99).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-$here/../build/release}
conns=${2:-100000}
secs=${3:-30}
sources=${4:-127.0.0.1-127.0.0.4}
mbstorm="$build/mbstorm"
[ -x "$mbstorm" ] || { echo "missing $mbstorm: build the release preset first" >&2; exit 1; }
out=$(mktemp -d /tmp/mbstorm-100k.XXXXXX)
rate=$((conns / 10))  # one request per connection every 10 s: about connections, not throughput

server_pid=""
client_pid=""
cleanup() {
  [ -n "$client_pid" ] && kill "$client_pid" 2>/dev/null || true
  [ -n "$server_pid" ] && kill "$server_pid" 2>/dev/null || true
  wait 2>/dev/null || true
}
trap cleanup EXIT

rss_kib() { awk '/^VmRSS/ {print $2}' "/proc/$1/status" 2>/dev/null || echo 0; }
tcp_inuse() { awk '/^TCP:/ {print $3}' /proc/net/sockstat; }
tcp_mem_pages() { awk '/^TCP:/ {print $11}' /proc/net/sockstat; }
conntrack() { cat /proc/sys/net/netfilter/nf_conntrack_count 2>/dev/null || echo "absent"; }

"$mbstorm" serve --listen 127.0.0.1:0 --max-connections $((conns + conns / 10)) >"$out/serve.log" 2>&1 &
server_pid=$!
for _ in $(seq 100); do grep -q "listening on" "$out/serve.log" && break; sleep 0.1; done
port=$(sed -n 's/.*listening on 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$out/serve.log" | head -1)
[ -n "$port" ] || { cat "$out/serve.log"; exit 1; }
head -1 "$out/serve.log"
server_idle_kib=$(rss_kib "$server_pid")

# One connection, same settings: the client's fixed memory (rings, buffers, histograms).
"$mbstorm" run --target "127.0.0.1:$port" -c 1 --depth 1 --rate 1 -d 3s -q \
  --source-addr "$sources" --json "$out/one.json" >"$out/one.log" 2>&1 &
client_pid=$!
base_kib=0
while kill -0 "$client_pid" 2>/dev/null; do
  r=$(rss_kib "$client_pid"); [ "${r:-0}" -gt "$base_kib" ] && base_kib=$r; sleep 0.2
done
wait "$client_pid" || true
client_pid=""

tcp_before=$(tcp_inuse)
start=$(date +%s.%N)
"$mbstorm" run --target "127.0.0.1:$port" -c "$conns" --depth 1 --rate "$rate" \
  --connect-rate 200000 --connect-timeout 10s --timeout 5s -d "${secs}s" --warmup 30s -q \
  --source-addr "$sources" --json "$out/run.json" >"$out/run.log" 2>&1 &
client_pid=$!
peak_client=0; peak_server=0; all_open_s=""; peak_tcp_mem=0; peak_conntrack=0
while kill -0 "$client_pid" 2>/dev/null; do
  c=$(rss_kib "$client_pid"); s=$(rss_kib "$server_pid")
  [ "${c:-0}" -gt "$peak_client" ] && peak_client=$c
  [ "${s:-0}" -gt "$peak_server" ] && peak_server=$s
  m=$(tcp_mem_pages); [ "$m" -gt "$peak_tcp_mem" ] && peak_tcp_mem=$m
  ct=$(conntrack); [ "$ct" != absent ] && [ "$ct" -gt "$peak_conntrack" ] && peak_conntrack=$ct
  if [ -z "$all_open_s" ] && [ $(( $(tcp_inuse) - tcp_before )) -ge $((2 * conns)) ]; then
    all_open_s=$(echo "$(date +%s.%N) - $start" | bc)
  fi
  sleep 0.2
done
rc=0; wait "$client_pid" || rc=$?
client_pid=""

echo "connections: $conns over $sources, ${secs}s measured after a 30s warm-up (connecting), exit code $rc"
if [ -n "$all_open_s" ]; then
  echo "all open after: ${all_open_s}s ($(echo "$conns / $all_open_s" | bc) connections/s, both ends counted)"
else
  echo "all open after: never (peak TCP sockets in use below 2 x $conns)"
fi
echo "client peak RSS: ${peak_client} KiB; 1-connection run: ${base_kib} KiB;" \
  "per connection: $(( (peak_client - base_kib) * 1024 / conns )) B"
echo "server RSS: idle ${server_idle_kib} KiB, peak ${peak_server} KiB;" \
  "per connection: $(( (peak_server - server_idle_kib) * 1024 / conns )) B"
echo "kernel TCP memory peak: ${peak_tcp_mem} pages ($(( peak_tcp_mem * 4 / 1024 )) MiB);" \
  "tcp_mem: $(cat /proc/sys/net/ipv4/tcp_mem); conntrack entries peak: ${peak_conntrack}"
python3 - "$out/run.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
t = r["totals"]; c = r["connections"]; p = r["latency"]["percentiles_ns"]
print("run:", {k: t.get(k) for k in ("transactions_sent", "ok", "errors")}, "connections:", c)
print("latency:", {k: f"{v / 1000:.0f} us" for k, v in p.items()})
PY
echo "files: $out"
