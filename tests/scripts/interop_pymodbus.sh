#!/usr/bin/env bash
# Interop: pymodbus 3.0 (Debian, /usr/bin/python3) and mbpoll against mbstorm's reference
# slave, started in-process by the test tool (tests/mbstorm_test_server next to the binary).
#   bash interop_pymodbus.sh <mbstorm-binary> <scripts-dir>
set -u
bin_dir=$(cd "$(dirname "$1")" && pwd)
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
tool="$bin_dir/tests/mbstorm_test_server"
[ -x "$tool" ] || { echo "missing $tool"; exit 1; }

source "$scripts/lib/peer.bash"
out=$(mktemp); trap 'stop_server; rm -f "$out"' EXIT
start_server "$out" "$tool" --threads 2 --seconds 120 || { echo "server did not start"; exit 1; }

fail=0
/usr/bin/python3 "$scripts/interop_pymodbus.py" "$port" || fail=1

if command -v mbpoll >/dev/null; then
  # mbpoll: references are 1-based (-r 1 is register 0). Write three registers, read them back.
  mbpoll -m tcp -p "$port" -a 1 -r 11 -t 4 -1 127.0.0.1 -- 101 202 303 >/dev/null 2>&1 \
    || { echo "FAIL mbpoll write registers"; fail=1; }
  got=$(mbpoll -m tcp -p "$port" -a 1 -r 11 -c 3 -t 4 -1 127.0.0.1 2>/dev/null | grep -E '^\[1[123]\]' | awk '{print $2}' | tr '\n' ' ')
  [ "$got" = "101 202 303 " ] && echo "ok   mbpoll FC16/FC03 round trip" \
    || { echo "FAIL mbpoll read back: '$got'"; fail=1; }
  got=$(mbpoll -m tcp -p "$port" -a 1 -r 1 -c 10 -1 127.0.0.1 2>/dev/null | grep -cE '^\[[0-9]+\]')
  [ "$got" = 10 ] && echo "ok   mbpoll read 10 holding registers" || { echo "FAIL mbpoll read 10: $got"; fail=1; }
  mbpoll -m tcp -p "$port" -a 1 -r 5 -t 0 -1 127.0.0.1 -- 1 >/dev/null 2>&1 || { echo "FAIL mbpoll write coil"; fail=1; }
  got=$(mbpoll -m tcp -p "$port" -a 1 -r 5 -c 1 -t 0 -1 127.0.0.1 2>/dev/null | grep -E '^\[5\]' | awk '{print $2}')
  [ "$got" = 1 ] && echo "ok   mbpoll coil round trip" || { echo "FAIL mbpoll coil: '$got'"; fail=1; }
  got=$(mbpoll -m tcp -p "$port" -a 1 -r 1 -c 4 -t 3 -1 127.0.0.1 2>/dev/null | grep -cE '^\[[0-9]+\]')
  [ "$got" = 4 ] && echo "ok   mbpoll input registers" || { echo "FAIL mbpoll input registers: $got"; fail=1; }
else
  echo "mbpoll not installed: skipped"
fi
exit $fail
