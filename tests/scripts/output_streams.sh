#!/usr/bin/env bash
# '-' is stdout for every report file of run and fuzz (never a file named '-'); progress and
# diagnostics go to stderr, so stdout can be piped: with a file on stdout, stdout holds that
# file alone; without, it holds the report alone.
#   bash output_streams.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
bin_dir=$(dirname "$mbstorm")
scripts=$(cd "$2" && pwd)
tool="$bin_dir/tests/mbstorm_test_server"
[ -x "$tool" ] || { echo "missing $tool"; exit 1; }
source "$scripts/lib/peer.bash"
work=$(mktemp -d)
trap 'stop_server; rm -rf "$work"' EXIT
cd "$work"
fail=0
ok() { echo "ok   $1"; }
bad() { echo "FAIL $1"; sed 's/^/  out: /' out | head -5; sed 's/^/  err: /' err | head -5; fail=1; }
is_json() { /usr/bin/python3 -c 'import json,sys; json.load(open(sys.argv[1]))' "$1" 2>/dev/null; }

"$mbstorm" run -d 1s -c 1 --depth 1 --json - >out 2>err
if [ $? = 0 ] && is_json out && [ ! -e ./- ] && grep -q Throughput err; then ok "run --json -: stdout is the JSON alone, the report on stderr"
else bad "run --json -"; fi

"$mbstorm" run -d 1s -c 1 --depth 1 --hdr - -q >out 2>err
if [ $? = 0 ] && grep -q '^#\[Mean' out && ! grep -q Throughput out && [ ! -e ./- ]; then ok "run --hdr -: stdout is the .hgrm alone"
else bad "run --hdr -"; fi

"$mbstorm" run -d 2s -c 1 --depth 1 >out 2>err
if [ $? = 0 ] && grep -q Throughput out && ! grep -q 'mbstorm run:' out && grep -q 'mbstorm run: load test' err &&
   grep -q 'tx/s' err; then ok "run: the report on stdout, diagnostics and progress on stderr"
else bad "run without files"; fi

"$mbstorm" run -d 1s --json - --html - >out 2>err
if [ $? = 2 ] && grep -q "only one of" err; then ok "run: two files on stdout is a usage error"
else bad "run --json - --html -"; fi

start_server "$work/server.out" "$tool" --threads 1 --seconds 120 || { echo "FAIL server did not start"; exit 1; }
"$mbstorm" fuzz --target "127.0.0.1:$port" -d 1500ms --no-minimize --out "$work/findings" --json - >out 2>err
code=$?
if [ $code -le 1 ] && is_json out && [ ! -e ./- ] && grep -q 'WARNING' err && grep -q '^\[ *[0-9.]*s\]' err; then
  ok "fuzz --json -: stdout is the JSON alone, warning and progress on stderr"
else bad "fuzz --json - (exit $code)"; fi

"$mbstorm" fuzz --target "127.0.0.1:$port" -d 1500ms --no-minimize --out "$work/findings" >out 2>err
code=$?
if [ $code -le 1 ] && ! grep -q '^\[ *[0-9.]*s\]\|WARNING' out && grep -q 'fuzz summary' out && grep -q '^\[ *[0-9.]*s\]' err; then
  ok "fuzz: the summary on stdout, progress on stderr"
else bad "fuzz without files (exit $code)"; fi
exit $fail
