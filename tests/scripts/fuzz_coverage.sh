#!/usr/bin/env bash
# mbstorm fuzz --coverage (issue #27), as a user who can rebuild their server runs it: a small
# C device (tests/tools/coverage_device.c) built with clang -fsanitize-coverage=
# trace-pc-guard,trace-cmp and mbstorm's runtime (coverage/mbstorm_coverage.c), started by
# mbstorm (--target-cmd). Its two planted crashes each need two fields equal to constants at
# once (1 in 2^32 for a guess): coverage mode must find both, with edges that only grow, and
# each reproducer must crash the device again when replayed alone; the black-box mode, the same
# device built without coverage, the same seed and time, finds neither. Built with AFL++'s
# afl-clang-fast the device works unchanged. --html writes the run as a page (the edges chart
# and the findings); built with pc-table too, --coverage-report names the device's maintenance
# routine (a signal handler) as never reached, and not its request handler.
#   bash fuzz_coverage.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
root=$(cd "$scripts/../.." && pwd)
source "$scripts/lib/peer.bash"
work=$(mktemp -d)
trap 'stop_server; rm -rf "$work"' EXIT
seconds=20

# bounded SECONDS COMMAND...: COMMAND, killed if it outlives SECONDS.
bounded() { timeout -k 5 "$@"; }

fail=0
device="$root/tests/tools/coverage_device.c"
runtime="$root/coverage/mbstorm_coverage.c"
clang -O1 -g -fsanitize-coverage=trace-pc-guard,trace-cmp,pc-table -c "$device" -o "$work/device.o" &&
  clang -O1 -c "$runtime" -o "$work/runtime.o" &&
  clang "$work/device.o" "$work/runtime.o" -o "$work/device-coverage" &&
  clang -O1 -g -fsanitize-coverage=trace-pc-guard,trace-cmp -c "$device" -o "$work/device-nopc.o" &&
  clang "$work/device-nopc.o" "$work/runtime.o" -o "$work/device-nopc" &&
  clang -O1 -g "$device" -o "$work/device-plain" ||
  { echo "FAIL: the device does not build with clang and the coverage runtime"; exit 1; }

# A port for the device: mbstorm starts it there (and again after each crash).
free_port() { /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }

# fuzz_device NAME BINARY [FLAGS...]: fuzzes BINARY started by mbstorm; $work/NAME.json.
fuzz_device() {
  local name=$1 binary=$2; shift 2
  local p; p=$(free_port)
  bounded $((seconds + 40)) "$mbstorm" fuzz --target "127.0.0.1:$p" --target-cmd "exec $binary --port $p" \
    --seconds "$seconds" --seed 1 -q --no-model --max-connections 0 --out "$work/$name" --json "$work/$name.json" "$@" \
    >"$work/$name.log" 2>&1
  local rc=$?
  if [ "$rc" -ne 0 ] && [ "$rc" -ne 1 ]; then
    echo "FAIL $name: exit $rc"; sed 's/^/  /' "$work/$name.log" | tail -20; fail=1
  fi
}

fuzz_device coverage "$work/device-coverage" --coverage --html "$work/coverage.html" \
  --coverage-report "$work/unreached.txt"
fuzz_device blackbox "$work/device-plain" --html "$work/blackbox.html"
/usr/bin/python3 - "$work/coverage.json" "$work/blackbox.json" <<'PY' || fail=1
import json, sys
planted = {"crash:target-down/fc06", "crash:target-down/fc16"}
cov, bb = (json.load(open(p)) for p in sys.argv[1:3])
found = {f["root_cause"] for f in cov["findings"]}
over_time = [e for _, e in cov["coverage"]["edges_over_time"]]
checks = [
    (planted == found, f"coverage mode finds both planted crashes, nothing else (found {sorted(found)})"),
    (cov["coverage"]["edges"] > 20 and cov["coverage"]["corpus"] > 5,
     f"edges {cov['coverage']['edges']}, corpus {cov['coverage']['corpus']}"),
    (over_time == sorted(over_time) and len(over_time) > 1, "edges only grow over time"),
    (cov["coverage"]["compared_constants"] > 0, "constants read from the device's comparisons"),
    (sum(cov["coverage"]["edges_by_function"].values()) == cov["coverage"]["edges"]
     and {"0x03", "0x06", "0x10", "0x16"} <= set(cov["coverage"]["edges_by_function"]),
     f"new edges by function code: {cov['coverage']['edges_by_function']}"),
    (not planted & {f["root_cause"] for f in bb["findings"]},
     f"the black-box mode finds neither in the same time ({bb['cases']} cases)"),
    (bb["coverage"] is None, "a black-box run reports no coverage"),
]
for ok, what in checks:
    print(("ok   " if ok else "FAIL ") + what)
sys.exit(0 if all(ok for ok, _ in checks) else 1)
PY

# --html: one page with the run, the findings (both planted crashes, with their folders) and,
# in coverage mode only, the edges chart and the edges by function code.
html_fail=0
html_has() { grep -q -- "$2" "$1" || { echo "FAIL $(basename "$1") lacks '$2'"; html_fail=1; }; }
for part in '<svg' 'Edges reached over time' '<polyline' 'crash:target-down/fc06' \
  'crash:target-down/fc16' '001-crash-target-down-fc' '0x10 write_multiple_registers' \
  'time limit reached' 'cases/s'; do
  html_has "$work/coverage.html" "$part"
done
html_has "$work/blackbox.html" 'No findings'
if grep -q '<svg' "$work/blackbox.html"; then echo "FAIL the black-box page has a chart"; html_fail=1; fi
[ "$html_fail" -eq 0 ] && echo "ok   --html: the chart, the edges by function code and the findings" || fail=1

# --coverage-report: the maintenance routine only a signal runs is listed, with its file and
# line; the request handler every case runs and main are not.
report="$work/unreached.txt"
if [ -f "$report" ] &&
  grep -qE '^[0-9]+ of [0-9]+ functions reached; never reached: [0-9]+$' <(head -1 "$report") &&
  grep -qE '^clear_registers +.*coverage_device\.c:[0-9]+$' "$report" &&
  ! grep -qE '^(answer|main) ' "$report"; then
  echo "ok   --coverage-report: $(head -1 "$report"), clear_registers among them, answer not"
else
  echo "FAIL --coverage-report:"; sed 's/^/  /' "$report" 2>/dev/null | head -20; fail=1
fi
# A target built without pc-table lists no functions: said so, no file, exit 2 (a report that
# could not be written); and the report is refused without --coverage.
p=$(free_port)
bounded 40 "$mbstorm" fuzz --target "127.0.0.1:$p" --target-cmd "exec $work/device-nopc --port $p" \
  --coverage --seconds 2 -q --no-model --max-connections 0 --out "$work/nopc" \
  --coverage-report "$work/nopc.txt" >"$work/nopc.log" 2>&1
rc=$?
if [ "$rc" -eq 2 ] && grep -q 'the target was built without pc-table' "$work/nopc.log" &&
  [ ! -e "$work/nopc.txt" ]; then
  echo "ok   a target without pc-table: named, no report, exit 2"
else
  echo "FAIL without pc-table: exit $rc"; sed 's/^/  /' "$work/nopc.log" | tail -5; fail=1
fi
"$mbstorm" fuzz --target 127.0.0.1:1 --seconds 1 --coverage-report "$work/x.txt" >"$work/refused.log" 2>&1
rc=$?
if [ "$rc" -eq 2 ] && grep -q -- '--coverage-report .*needs --coverage' "$work/refused.log"; then
  echo "ok   --coverage-report without --coverage: refused, exit 2"
else
  echo "FAIL --coverage-report without --coverage: exit $rc"; sed 's/^/  /' "$work/refused.log"; fail=1
fi

# --corpus: the corpus saved one file per entry, and a later run resumes from it (the saved
# entries run first, so it is where the first run ended within its first second).
seconds=4 fuzz_device saved "$work/device-coverage" --coverage --corpus "$work/corpus"
saved=$(find "$work/corpus" -name '*.json' | wc -l)
seconds=3 fuzz_device resumed "$work/device-coverage" --coverage --corpus "$work/corpus"
/usr/bin/python3 - "$work/saved.json" "$work/resumed.json" "$saved" <<'PY' || fail=1
import json, sys
first, again = (json.load(open(p))["coverage"] for p in sys.argv[1:3])
saved = int(sys.argv[3])
at_one_second = max([e for t, e in again["edges_over_time"] if t < 1.0] or [0])
ok = saved == first["corpus"] and again["resumed"] == saved and at_one_second >= first["edges"] - 2
print(("ok   " if ok else "FAIL ") + f"--corpus: {saved} entries saved of {first['corpus']}, "
      f"{again['resumed']} resumed, {at_one_second} edges within 1 s of the resumed run "
      f"(the first ended at {first['edges']})")
sys.exit(0 if ok else 1)
PY

# Built with AFL++'s compiler instead, unchanged: its runtime writes the same map. (It logs no
# comparisons for mbstorm, so the planted crashes stay out of reach: only the map is checked.)
if AFL_QUIET=1 afl-clang-fast -O1 -g "$device" -o "$work/device-afl" >"$work/afl.log" 2>&1; then
  seconds=5 fuzz_device afl "$work/device-afl" --coverage
  /usr/bin/python3 - "$work/afl.json" <<'PY' || fail=1
import json, sys
j = json.load(open(sys.argv[1]))
ok = j["coverage"]["edges"] > 20 and j["coverage"]["corpus"] > 5 and not j["findings"]
print(("ok   " if ok else "FAIL ") + f"afl-clang-fast build: {j['coverage']['edges']} edges, "
      f"corpus {j['coverage']['corpus']}, {len(j['findings'])} findings, {j['cases']} cases")
sys.exit(0 if ok else 1)
PY
else
  echo "FAIL: the device does not build with afl-clang-fast"; sed 's/^/  /' "$work/afl.log"; fail=1
fi

# The target mbstorm started is stopped at the end of the run, and dies with mbstorm when
# mbstorm is killed outright.
left=$(pgrep -f "$work/device-" || true)
[ -z "$left" ] && echo "ok   the targets were stopped at the end of each run" ||
  { echo "FAIL target processes left running: $left"; fail=1; }
p=$(free_port)
"$mbstorm" fuzz --target "127.0.0.1:$p" --target-cmd "exec $work/device-plain --port $p" \
  --seconds 30 -q --max-connections 0 --out "$work/killed" >/dev/null 2>&1 &
fuzzer=$!
for _ in $(seq 50); do pgrep -f "$work/device-plain" >/dev/null && break; sleep 0.1; done
sleep 0.5
kill -9 "$fuzzer"; wait "$fuzzer" 2>/dev/null
for _ in $(seq 20); do pgrep -f "$work/device-plain" >/dev/null || break; sleep 0.1; done
if pgrep -f "$work/device-plain" >/dev/null; then
  echo "FAIL the target outlived a killed mbstorm"; pkill -f "$work/device-plain"; fail=1
else
  echo "ok   the target died with a killed mbstorm"
fi

# Each crash replays alone against the device built with coverage, run on its own (no map
# handed to it: the runtime counts into a private one).
for folder in "$work"/coverage/*crash*/; do
  [ -f "$folder/finding.json" ] || continue
  if ! start_server "$work/replay.out" "$work/device-coverage" --port 0; then
    echo "FAIL: the device did not start for replay"; fail=1; break
  fi
  out=$(bounded 30 "$mbstorm" replay "$folder" --target "127.0.0.1:$port" --runs 1 2>&1)
  if [ $? -eq 1 ] && grep -q "1 of 1 run(s) reproduced" <<<"$out"; then
    echo "ok   replay reproduces $(basename "$folder")"
  else
    echo "FAIL replay of $(basename "$folder")"; sed 's/^/  /' <<<"$out"; fail=1
  fi
  stop_server
done
exit $fail
