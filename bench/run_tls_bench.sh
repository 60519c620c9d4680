#!/usr/bin/env bash
# --transport tls against plain TCP (results go into bench/README.md).
#
#   bench/run_tls_bench.sh [build-dir] [seconds-per-run]
#
# `mbstorm serve` (1 thread) pinned to core 0, `mbstorm run` (1 thread) pinned to core 1,
# certificates from tests/scripts/lib/tls_certs.bash (ECDSA P-256).
#  1. Throughput and p99 at 16 connections x depth 16, FC03 x 10: plain TCP, then TLS.
#  2. Handshakes per second: the server closes a connection instead of answering half of
#     the requests (--drop-rate 0.5; not all, so that the TLS 1.3 tickets, sent with the
#     first answer, reach the client), 200 connections reopen (100 ms backoff each), with
#     and without --tls-resume; the report's handshake count over the run's time.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-$here/../build/release}
secs=${2:-5}
mbstorm="$build/mbstorm"
[ -x "$mbstorm" ] || { echo "missing $mbstorm: build the release preset first" >&2; exit 1; }
work=$(mktemp -d)
server_pid=""
cleanup() {
  [ -n "$server_pid" ] && kill "$server_pid" 2>/dev/null
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
source "$here/../tests/scripts/lib/tls_certs.bash"
make_tls_certs "$work"
server_tls=(--transport tls --tls-ca "$work/ca.pem" --tls-cert "$work/server.pem"
            --tls-key "$work/server.key")
client_tls=(--transport tls --tls-ca "$work/ca.pem" --tls-cert "$work/operator.pem"
            --tls-key "$work/operator.key")

# serve ARGS...: starts the server on core 0, sets $port.
serve() {
  [ -n "$server_pid" ] && { kill "$server_pid"; wait "$server_pid" 2>/dev/null || true; }
  taskset -c 0 "$mbstorm" serve --listen 127.0.0.1:0 --threads 1 "$@" >"$work/serve.out" 2>&1 &
  server_pid=$!
  port=""
  for _ in $(seq 100); do
    port=$(sed -n 's/.*listening on 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$work/serve.out")
    [ -n "$port" ] && return 0
    sleep 0.1
  done
  echo "server did not start" >&2; exit 1
}
# measure NAME ARGS...: one run on core 1, one line of results.
measure() {
  local name=$1; shift
  taskset -c 1 "$mbstorm" run --target "127.0.0.1:$port" --threads 1 -d "${secs}s" --warmup 1s \
    --json "$work/run.json" "$@" >/dev/null 2>&1 || true
  /usr/bin/python3 - "$name" "$work/run.json" "$secs" <<'PY'
import json, sys
name, path, secs = sys.argv[1], sys.argv[2], float(sys.argv[3])
r = json.load(open(path)); t = r["totals"]; c = r["connections"]
hs = c.get("tls_handshakes", 0)
line = f"{name:34s} {t['throughput_per_s']:>10.0f} tx/s  p99 {r['latency']['percentiles_ns']['99']/1e3:>8.0f} us"
if hs:
    line += (f"  handshakes {hs} ({hs/(secs+1):.0f}/s), resumed {c['tls_resumed']},"
             f" mean {c['tls_handshake_ns_total']/hs/1e6:.2f} ms")
print(line)
PY
}

echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
serve
measure "plain TCP 16x16" -c 16 --depth 16 --fc 3 --quantity 10
serve "${server_tls[@]}"
measure "TLS 16x16" "${client_tls[@]}" -c 16 --depth 16 --fc 3 --quantity 10
serve "${server_tls[@]}" --drop-rate 0.5
measure "TLS handshakes, full" "${client_tls[@]}" -c 200 --depth 1 --connect-rate 100000
measure "TLS handshakes, --tls-resume" "${client_tls[@]}" -c 200 --depth 1 \
  --connect-rate 100000 --tls-resume
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
