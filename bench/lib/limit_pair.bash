# Sourced by run_backend_bench.sh and run_seam_bench.sh: the limit pair (bench/tools'
# limit_server and pipeline_client) and mbstorm on either end of it, the server pinned to
# core 0 and the client to core 1. Needs $limit and $client (the tools' paths) and $secs (the
# measured seconds of each client run, after 1 s of warm-up).

server_pid=""

# stop_server: stops and reaps the server started last (safe to call twice).
stop_server() {
  if [ -n "$server_pid" ]; then kill "$server_pid" 2>/dev/null; wait "$server_pid" 2>/dev/null; fi
  server_pid=""
}

# median: the median of numbers separated by spaces or newlines on stdin.
median() { tr ' ' '\n' | grep -v '^$' | sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }

# start_limit: limit_server on core 0; sets $server_pid and $port (from its "PORT <n>" line).
start_limit() {
  local out; out=$(mktemp)
  taskset -c 0 "$limit" --seconds 3600 >"$out" 2>/dev/null & server_pid=$!
  for _ in $(seq 100); do grep -q PORT "$out" && break; sleep 0.05; done
  port=$(awk '/PORT/ {print $2}' "$out"); rm -f "$out"
}

# start_serve MBSTORM BACKEND: `mbstorm serve` of that binary, one thread, on core 0.
start_serve() {
  port=$((20000 + RANDOM % 20000))
  taskset -c 0 "$1" serve --backend "$2" --listen "127.0.0.1:$port" --threads 1 \
    --max-connections 0 >/dev/null 2>&1 & server_pid=$!
  sleep 0.5
}

# pair_client CONNECTIONS DEPTH: pipeline_client's transactions/s against $port.
pair_client() {
  taskset -c 1 "$client" --port "$port" --connections "$1" --depth "$2" --seconds "$secs" \
    --warmup 1 2>/dev/null | sed -n 's/^RESULT tps=\([0-9]*\).*/\1/p'
}

# mbstorm_client MBSTORM BACKEND CONNECTIONS DEPTH: `mbstorm run`'s transactions/s against $port,
# one thread on core 1 (read from its --json report).
mbstorm_client() {
  local json; json=$(mktemp)
  taskset -c 1 "$1" run --backend "$2" --target "127.0.0.1:$port" --threads 1 -c "$3" \
    --depth "$4" -d "${secs}s" --warmup 1s -q --json "$json" >/dev/null 2>&1
  /usr/bin/python3 -c 'import json,sys;print(round(json.load(open(sys.argv[1]))["totals"]["throughput_per_s"]))' "$json"
  rm -f "$json"
}
