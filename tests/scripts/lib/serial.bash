# Sourced by the serial script tests: a pseudo-terminal pair joined by socat, a null-modem
# cable with no baud-rate timing of its own.
#
#   serial_prologue
# What every serial script begins with: $work, a folder removed at exit (kept when KEEP_WORK is
# set) with the server and socat stopped, and a skip (exit 77) when socat is missing.
serial_prologue() {
  work=$(mktemp -d)
  trap 'stop_server; stop_pty_pair; [ -n "${KEEP_WORK:-}" ] || rm -rf "$work"' EXIT
  command -v socat >/dev/null || { echo "skip: socat not installed"; exit 77; }
}

#   start_pty_pair DIR
# Starts socat with two ptys linked as DIR/line_a and DIR/line_b; sets $socat_pid. Returns
# non-zero if the links do not appear within 5 s.
start_pty_pair() {
  local dir=$1
  socat pty,raw,echo=0,link="$dir/line_a" pty,raw,echo=0,link="$dir/line_b" 2>/dev/null &
  socat_pid=$!
  for _ in $(seq 50); do
    [ -e "$dir/line_a" ] && [ -e "$dir/line_b" ] && return 0
    sleep 0.1
  done
  return 1
}

# stop_pty_pair: stops and reaps socat (safe to call twice).
stop_pty_pair() {
  if [ -n "${socat_pid:-}" ]; then kill "$socat_pid" 2>/dev/null; wait "$socat_pid" 2>/dev/null; fi
  socat_pid=""
}

# start_serial_serve OUTFILE MBSTORM DEVICE [SERVE_ARGS...]: `MBSTORM serve --serial DEVICE`
# in the background; sets $server_pid once it says it serves (up to 10 s).
start_serial_serve() {
  local out=$1 mbstorm=$2 device=$3; shift 3
  "$mbstorm" serve --serial "$device" "$@" >"$out" 2>"$out.err" &
  server_pid=$!
  for _ in $(seq 100); do
    grep -q "serving on" "$out" && return 0
    kill -0 "$server_pid" 2>/dev/null || return 1
    sleep 0.1
  done
  return 1
}
