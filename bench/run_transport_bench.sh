#!/usr/bin/env bash
# Each transport of `mbstorm run` against `mbstorm serve` speaking it, at the same shape:
# 16 connections x depth 1 (RTU over TCP has no transaction ids, so depth 1 is its only shape),
# one engine thread, one slave thread. Prints throughput and p99 per repeat.
#   bench/run_transport_bench.sh BUILD_DIR [REPEATS] [SECONDS]
set -eu
build=$1; repeats=${2:-3}; seconds=${3:-5}
mbstorm="$build/mbstorm"
work=$(mktemp -d)
serve_pid=""
trap '[ -n "$serve_pid" ] && kill "$serve_pid" 2>/dev/null; rm -rf "$work"' EXIT
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
printf '%-14s %6s %12s %10s\n' transport repeat "tx/s" "p99 us"
for r in $(seq "$repeats"); do
  for transport in tcp rtu-over-tcp; do
    port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
    "$mbstorm" serve --transport "$transport" --listen "127.0.0.1:$port" --threads 1 >"$work/serve.out" 2>&1 &
    serve_pid=$!
    for _ in $(seq 100); do grep -q "listening on" "$work/serve.out" && break; sleep 0.1; done
    "$mbstorm" run --transport "$transport" --target "127.0.0.1:$port" --threads 1 -c 16 --depth 1 \
      -d "${seconds}s" --warmup 1s -q --json "$work/run.json" >/dev/null 2>&1 || true
    kill "$serve_pid"; wait "$serve_pid" 2>/dev/null || true; serve_pid=""
    /usr/bin/python3 - "$work/run.json" "$transport" "$r" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
errors = d["totals"]["errors"]
print(f"{sys.argv[2]:<14} {sys.argv[3]:>6} {d['totals']['throughput_per_s']:>12.0f} "
      f"{d['latency']['percentiles_ns']['99'] / 1000:>10.1f}" + (f"   ({errors} errors)" if errors else ""))
PY
  done
done
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
