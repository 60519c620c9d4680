#!/usr/bin/env bash
# Interop: `mbstorm write` and `mbstorm read` against pymodbus 3.0's asyncio server (Debian,
# /usr/bin/python3): typed values round-trip through a server mbstorm did not write, and an
# exception answer is named with exit code 1.
#   bash read_write_pymodbus.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
pymodbus_server="$scripts/../../bench/peers/pymodbus_server.py"

source "$scripts/lib/peer.bash"
work=$(mktemp -d)
trap 'stop_server; rm -rf "$work"' EXIT

if [ ! -f "$pymodbus_server" ] || ! /usr/bin/python3 -c 'import pymodbus' 2>/dev/null; then
  echo "skip: pymodbus not installed"; exit 77
fi
start_server "$work/peer.out" /usr/bin/python3 "$pymodbus_server" --seconds 60 || {
  echo "FAIL: pymodbus server did not start"; exit 1; }
target=127.0.0.1:$port

fail=0
# expect <name> <wanted exit code> <wanted text> <mbstorm args...>
expect() {
  local name=$1 code=$2 text=$3; shift 3
  local out rc
  out=$(timeout -k 5 30 "$mbstorm" "$@" --target "$target" 2>&1); rc=$?
  if [ "$rc" = "$code" ] && [[ "$out" == *"$text"* ]]; then echo "ok   $name"
  else echo "FAIL $name: exit $rc, wanted $code and '$text'"; sed 's/^/  /' <<<"$out"; fail=1; fi
}

expect "f32 CDAB written" 0 "wrote 4 register(s)" write --addr 40011 --type f32 --order CDAB 3.5 -1.25
expect "f32 CDAB read back" 0 $'[10]: 3.5\n[12]: -1.25' read --addr 40011 --quantity 2 --type f32 --order CDAB
expect "string written" 0 "wrote 4 register(s)" write --addr 20 --type string pymodbus
expect "string read back" 0 "[20]: pymodbus" read --addr 20 --type string --quantity 8
expect "coils round trip" 0 "wrote 3 bit(s)" write --addr 00006 1 1 0
expect "coils read back" 0 $'[5]: 1\n[6]: 1\n[7]: 0' read --addr 00006 --quantity 3
expect "exception named" 1 "ILLEGAL DATA ADDRESS" read --addr 0x1000
exit $fail
