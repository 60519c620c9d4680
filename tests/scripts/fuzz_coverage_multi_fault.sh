#!/usr/bin/env bash
# mbstorm fuzz --coverage (issue #27) on both multi-fault targets of tests/tools/
# (multi_fault_server.cpp, 12 planted bugs; sparse_device_server.cpp, 13), each built with
# clang++ -fsanitize-coverage=trace-pc-guard,trace-cmp and mbstorm's runtime and started as a
# plain process by mbstorm (--target-cmd; mbstorm restarts it after each crash). Every planted
# bug must be found, each once, and nothing else (the sparse device's flush after exceptions,
# a fault it has like libmodbus, aside): among them one bug per target that needs one value at
# one address, which the black-box mode does not reach (tests/netfuzz/multi_fault_test.cpp and
# sparse_fault_test.cpp check that it does not), and whose reproducer must crash the target
# again. Edges only grow. A correct server (the reference handler behind the same poll() loop,
# tests/tools/reference_poll_server.cpp, the slave code instrumented too) gives no findings in
# 30 s. A crash in frames sent together is filed under the request that kills alone. Built
# with AFL++'s afl-clang-fast++ instead, each target works unchanged (the map only).
#
# The project's codec and slave code the targets link is built here without coverage: the
# planted bugs are in the targets' own sources, whose edges and comparisons are what has to
# guide the search, and the objects then link whatever the build's flavour (the sanitizer build
# compiles its libraries with ASan).
#   bash fuzz_coverage_multi_fault.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
root=$(cd "$scripts/../.." && pwd)
source "$scripts/lib/peer.bash"
work=$(mktemp -d)
trap 'stop_server; [ -n "${KEEP_WORK:-}" ] || rm -rf "$work"' EXIT

# bounded SECONDS COMMAND...: COMMAND, killed if it outlives SECONDS.
bounded() { timeout -k 5 "$@"; }

fail=0
cov_flags=(-fsanitize-coverage=trace-pc-guard,trace-cmp)
cxx_flags=(-std=c++20 -O1 -I"$root/src")
libs=(codec/pdu_request codec/pdu_records codec/function_code slave/handler slave/data_model)

# build_all: the shared objects, then each target (two at a time: two cores).
build_lib() { clang++ "${cxx_flags[@]}" "$@"; }
wait_all() { local p rc=0; for p; do wait "$p" || rc=1; done; return $rc; }
build_all() {
  local src pids=()
  for src in "${libs[@]}"; do
    build_lib -c "$root/src/$src.cpp" -o "$work/$(basename "$src").o" & pids+=($!)
    build_lib "${cov_flags[@]}" -c "$root/src/$src.cpp" -o "$work/$(basename "$src")-cov.o" & pids+=($!)
    wait_all "${pids[@]}" || return 1
    pids=()
  done
  clang -O1 -c "$root/coverage/mbstorm_coverage.c" -o "$work/runtime.o" || return 1
  local plain=() cov=()
  for src in "${libs[@]}"; do
    plain+=("$work/$(basename "$src").o")
    cov+=("$work/$(basename "$src")-cov.o")
  done
  local name
  for name in multi_fault_server sparse_device_server; do
    build_lib "${cov_flags[@]}" "$root/tests/tools/$name.cpp" "${plain[@]}" "$work/runtime.o" \
      -o "$work/$name-coverage" & pids+=($!)
    AFL_QUIET=1 afl-clang-fast++ "${cxx_flags[@]}" "$root/tests/tools/$name.cpp" "${plain[@]}" \
      -o "$work/$name-afl" & pids+=($!)
    wait_all "${pids[@]}" || return 1
    pids=()
  done
  build_lib "${cov_flags[@]}" "$root/tests/tools/reference_poll_server.cpp" "${cov[@]}" \
    "$work/runtime.o" -o "$work/reference-coverage"
}
build_all >"$work/build.log" 2>&1 ||
  { echo "FAIL: the targets do not build with clang++/afl-clang-fast++"; tail -20 "$work/build.log"; exit 1; }

# A port for a target: mbstorm starts it there (and again after each crash).
free_port() { /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }

# fuzz_target NAME BINARY SECONDS [FLAGS...]: fuzzes BINARY started by mbstorm; $work/NAME.json.
fuzz_target() {
  local name=$1 binary=$2 seconds=$3; shift 3
  local p; p=$(free_port)
  bounded $((seconds + 60)) "$mbstorm" fuzz --target "127.0.0.1:$p" --target-cmd "exec $binary --port $p" \
    --seconds "$seconds" --seed 1 -q --out "$work/$name" --json "$work/$name.json" "$@" \
    >"$work/$name.log" 2>&1
  local rc=$?
  if [ "$rc" -ne 0 ] && [ "$rc" -ne 1 ]; then
    echo "FAIL $name: exit $rc"; sed 's/^/  /' "$work/$name.log" | tail -20; fail=1
  fi
}

# check_run JSON PLANTED ALLOWED: every planted root cause once, nothing else but ALLOWED (each
# a comma-separated list), edges that only grow, comparisons read.
check_run() {
  /usr/bin/python3 - "$@" <<'PY'
import json, sys
path, planted, allowed = sys.argv[1], set(sys.argv[2].split(",")), set(filter(None, sys.argv[3].split(",")))
j = json.load(open(path))
found = [f["root_cause"] for f in j["findings"]]
cov = j["coverage"]
over_time = [e for _, e in cov["edges_over_time"]]
name = path.rsplit("/", 1)[-1][:-5]
times = {f["root_cause"]: f["found_after_s"] for f in j["findings"]}
checks = [
    (planted <= set(found), f"{name}: every planted bug found ({len(planted & set(found))} of "
     f"{len(planted)}; missing {sorted(planted - set(found))}) in {j['seconds']:.0f} s, "
     f"{j['cases']} cases"),
    (len(found) == len(set(found)) and set(found) <= planted | allowed,
     f"{name}: each once, nothing unplanted (found {sorted(set(found) - planted) or 'nothing else'})"),
    (over_time == sorted(over_time) and len(over_time) > 1 and cov["edges"] > 50,
     f"{name}: {cov['edges']} edges, only growing; corpus {cov['corpus']}"),
    (cov["compared_constants"] > 0, f"{name}: {cov['compared_constants']} constants read"),
]
for ok, what in checks:
    print(("ok   " if ok else "FAIL ") + what)
for key in sorted(times, key=times.get):
    print(f"       {times[key]:6.2f} s  {key}")
# What an unplanted finding was, so that a failed run says what to fix.
for f in j["findings"]:
    if f["root_cause"] not in planted | allowed:
        print(f"       unplanted {f['root_cause']}: {f['summary']} (case {f.get('case_number')}, "
              f"{f.get('note') or f.get('minimize_note') or ''}) {f.get('folder', '')}")
sys.exit(0 if all(ok for ok, _ in checks) else 1)
PY
}

# Blame: a split case, resumed from a corpus, that holds a report-server-id request and then
# one that crashes the target (FC 2B/0E code 04, object 80). The target answers what one read
# brought in one write, so the frames sent whole (the plain case the transport case is judged
# as) leave the first request unanswered: the crash must be filed under the request that kills
# alone, fc2B, not fc11 (as it was, in clean-clone CI runs, from a case the fuzzer made).
mkdir -p "$work/blame-corpus"
cat >"$work/blame-corpus/000000.json" <<'JSON'
{"class": "split", "function": 17, "steps": [
 {"op": "send", "conn": 0, "hex": "0001000000020111000200"},
 {"op": "send", "conn": 0, "hex": "000005012b0e0480"}]}
JSON
fuzz_target blame "$work/multi_fault_server-coverage" 15 --coverage --corpus "$work/blame-corpus"
/usr/bin/python3 - "$work/blame.json" <<'PY' || fail=1
import json, sys
j = json.load(open(sys.argv[1]))
crashes = {f["root_cause"]: f["class"] for f in j["findings"] if f["oracle"] == "crash"}
ok = crashes.get("crash:target-down/fc2B") == "coalesced" and "crash:target-down/fc11" not in crashes
print(("ok   " if ok else "FAIL ") + "blame: the coalesced frames' crash is filed under the request "
      f"that kills alone (crashes: {crashes})")
sys.exit(0 if ok else 1)
PY

multi_planted="crash:target-down/fc0F,crash:target-down/fc16,crash:target-down/fc2B"
multi_planted+=",hang:whole-server-hang/fc14,spec-deviation:answers-nonzero-protocol-id"
multi_planted+=",spec-deviation:exception-02-where-03-owed,hang:no-answer/fc07"
multi_planted+=",spec-deviation:read-after-write-mismatch(holding-registers)/fc17"
multi_planted+=",hang:stalls-other-connections(partial-frame)"
multi_planted+=",hang:capacity/accepted-connections-unserved"
multi_planted+=",unexpected-close:drops-answers-on-half-close,crash:target-down/fc06"
# The deadlines are far beyond what a release build needs (about 25 s and 35-65 s): the run ends
# at the last planted bug (--max-findings), and the sanitized build fuzzes slower.
fuzz_target multi "$work/multi_fault_server-coverage" 100 --coverage --max-findings 12
check_run "$work/multi.json" "$multi_planted" "" || fail=1

sparse_planted="crash:target-down/fc10,crash:target-down/fc0F,crash:target-down/fc17"
sparse_planted+=",crash:target-down/fc04"
sparse_planted+=",spec-deviation:read-after-write-mismatch(holding-registers)/fc16"
sparse_planted+=",spec-deviation:read-after-write-mismatch-other-connection(holding-registers)/fc06"
sparse_planted+=",malformed-response:echo-differs,hang:stalls-other-connections(partial-frame)"
sparse_planted+=",crash:target-down/capacity"
sparse_planted+=",spec-deviation:unmapped-address-answered-normally(holding_registers)"
sparse_planted+=",malformed-response:read-data-size,hang:no-answer/fc10,crash:target-down/fc01"
flush="hang:drops-requests-after-exception"
fuzz_target sparse "$work/sparse_device_server-coverage" 130 --coverage --max-findings 14
check_run "$work/sparse.json" "$sparse_planted" "$flush" || fail=1

# The bugs that need one value at one address: each reproducer crashes its target again, run
# on its own (no map handed to it: the runtime counts into a private one).
replay_crash() {
  local name=$1 binary=$2 rule=$3 folder
  folder=$(compgen -G "$work/$name/*-$rule" | head -1)
  if [ -z "$folder" ] || ! start_server "$work/replay.out" "$binary" --port 0; then
    echo "FAIL $name: no $rule finding to replay, or the target did not start"; fail=1; return
  fi
  local out; out=$(bounded 30 "$mbstorm" replay "$folder" --target "127.0.0.1:$port" --runs 1 2>&1)
  if [ $? -eq 1 ] && grep -q "1 of 1 run(s) reproduced" <<<"$out"; then
    echo "ok   $name: replay reproduces $(basename "$folder") ($(grep -o '"hex": "[0-9a-f]*"' "$folder/finding.json" | head -1))"
  else
    echo "FAIL $name: replay of $(basename "$folder")"; sed 's/^/  /' <<<"$out" | tail -5; fail=1
  fi
  stop_server
}
replay_crash multi "$work/multi_fault_server-coverage" crash-target-down-fc06
replay_crash sparse "$work/sparse_device_server-coverage" crash-target-down-fc01

# A correct server, built the same way with the slave code instrumented too: no findings.
fuzz_target reference "$work/reference-coverage" 30 --coverage
/usr/bin/python3 - "$work/reference.json" <<'PY' || fail=1
import json, sys
j = json.load(open(sys.argv[1]))
over_time = [e for _, e in j["coverage"]["edges_over_time"]]
ok = not j["findings"] and j["coverage"]["edges"] > 100 and over_time == sorted(over_time) \
    and j["seconds"] >= 29
print(("ok   " if ok else "FAIL ") + f"correct server: {len(j['findings'])} findings in "
      f"{j['seconds']:.0f} s, {j['cases']} cases, {j['coverage']['edges']} edges "
      f"({', '.join(f['root_cause'] for f in j['findings']) or 'as it should be'})")
sys.exit(0 if ok else 1)
PY

# Built with AFL++'s compiler instead, unchanged: its runtime writes the same map.
# (The sparse device needs longer: its learning waits out its pauses after exceptions.)
for name in multi_fault_server sparse_device_server; do
  seconds=4; [ "$name" = sparse_device_server ] && seconds=10
  fuzz_target "afl-$name" "$work/$name-afl" "$seconds" --coverage --max-connections 0
  /usr/bin/python3 - "$work/afl-$name.json" "$name" <<'PY' || fail=1
import json, sys
j = json.load(open(sys.argv[1]))
ok = j["coverage"]["edges"] > 50 and j["coverage"]["corpus"] > 5
print(("ok   " if ok else "FAIL ") + f"afl-clang-fast++ build of {sys.argv[2]}: "
      f"{j['coverage']['edges']} edges, corpus {j['coverage']['corpus']}, {j['cases']} cases")
sys.exit(0 if ok else 1)
PY
done

left=$(pgrep -f "$work/" || true)
[ -z "$left" ] && echo "ok   the targets were stopped at the end of each run" ||
  { echo "FAIL target processes left running: $left"; fail=1; }
exit $fail
