# Sourced by the end-to-end bench scripts: the contending servers, each pinned to core 0.
# Needs $build (the build directory); uses bench/peers/pymodbus_server.py from the source tree.

server_pid=""

# start_server <mbstorm|limit|libmodbus|pymodbus>: sets $server_pid and $port (read from the
# server's "PORT <n>" line, up to 10 s). Returns non-zero if the server never says it.
start_server() {
  local out; out=$(mktemp)
  local peers; peers=$(cd "$(dirname "${BASH_SOURCE[0]}")/../peers" && pwd)
  case "$1" in
    mbstorm)   taskset -c 0 "$build/tests/mbstorm_test_server" --threads 1 --seconds 3600 >"$out" 2>/dev/null & ;;
    limit)     taskset -c 0 "$build/bench/limit_server" --seconds 3600 >"$out" 2>/dev/null & ;;
    libmodbus) taskset -c 0 "$build/bench/libmodbus_server" --seconds 3600 >"$out" 2>/dev/null & ;;
    pymodbus)  taskset -c 0 /usr/bin/python3 "$peers/pymodbus_server.py" --seconds 3600 >"$out" 2>/dev/null & ;;
    *) echo "unknown server $1" >&2; rm -f "$out"; return 1 ;;
  esac
  server_pid=$!
  port=""
  for _ in $(seq 100); do
    port=$(awk '/^PORT/{print $2}' "$out"); [ -n "$port" ] && break; sleep 0.1
  done
  rm -f "$out"
  [ -n "$port" ]
}

# stop_server: stops and reaps what start_server started (safe to call twice).
stop_server() {
  if [ -n "$server_pid" ]; then kill "$server_pid" 2>/dev/null; wait "$server_pid" 2>/dev/null; fi
  server_pid=""
}
