# Sourced by the script tests: start a server that prints "PORT <n>" once it listens.
#
#   start_server OUTFILE COMMAND [ARGS...]
# Starts COMMAND in the background with stdout to OUTFILE; sets $server_pid, and $port once
# the line appears (up to 10 s). Returns non-zero if it never does.
start_server() {
  local out=$1; shift
  "$@" >"$out" 2>/dev/null &
  server_pid=$!
  port=""
  for _ in $(seq 100); do
    port=$(awk '/^PORT/{print $2}' "$out"); [ -n "$port" ] && return 0
    kill -0 "$server_pid" 2>/dev/null || return 1
    sleep 0.1
  done
  return 1
}

# stop_server: stops and reaps what start_server started (safe to call twice).
stop_server() {
  if [ -n "${server_pid:-}" ]; then kill "$server_pid" 2>/dev/null; wait "$server_pid" 2>/dev/null; fi
  server_pid=""
}

# wait_for SED_EXPRESSION FILE: sets $found to the first line `sed -n` prints from FILE, waiting
# up to 10 s for it to appear. Returns non-zero if it never does.
wait_for() {
  found=""
  for _ in $(seq 100); do
    found=$(sed -n "$1" "$2" | head -1); [ -n "$found" ] && return 0
    sleep 0.1
  done
  return 1
}

# start_mbstorm_serve OUTFILE MBSTORM [SERVE_ARGS...]: starts `MBSTORM serve --listen
# 127.0.0.1:0 SERVE_ARGS` in the background (stdout to OUTFILE, stderr to OUTFILE.err); sets
# $server_pid, and $port once serve says where it listens (up to 10 s). Non-zero if it never does.
start_mbstorm_serve() {
  local out=$1 mbstorm=$2; shift 2
  "$mbstorm" serve --listen 127.0.0.1:0 "$@" >"$out" 2>"$out.err" &
  server_pid=$!
  wait_for 's/.*listening on 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$out" || { port=""; return 1; }
  port=$found
}
