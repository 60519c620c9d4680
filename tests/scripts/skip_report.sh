#!/usr/bin/env bash
# scripts/skip_report.py, which test-all.sh runs after each test stage: it lists the tests that
# skipped, whole (CTest's notrun: GTEST_SKIP, a script's exit 77) or in part (a script that
# passed but skipped a peer), with their reasons; under CI=true it fails on any reason that
# scripts/allowed-skips.txt does not list (a missing program or module), and only then.
#   bash skip_report.sh <mbstorm-binary> <scripts-dir>
set -u
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
report="$scripts/../../scripts/skip_report.py"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0

# junit FILE CASES...: a CTest JUnit file; each case NAME|STATUS|OUTPUT.
junit() {
  local file=$1; shift
  { echo '<?xml version="1.0" encoding="UTF-8"?>'; echo '<testsuite name="(empty)" tests="3">'
    for c in "$@"; do
      IFS='|' read -r name status out <<<"$c"
      echo "<testcase name=\"$name\" classname=\"$name\" time=\"0.1\" status=\"$status\">"
      [ "$status" = notrun ] && echo '<skipped message="SKIP_RETURN_CODE=77"/>'
      printf '<system-out>%b</system-out></testcase>\n' "$out"
    done
    echo '</testsuite>'; } >"$file"
}

# expect NAME WANT_EXIT CI PATTERN FILE: runs the report, checks its exit and output.
expect() {
  local name=$1 want=$2 ci=$3 pattern=$4 file=$5
  out=$(CI=$ci /usr/bin/python3 "$report" "$file" stage 2>&1); rc=$?
  if [ "$rc" = "$want" ] && grep -qE "$pattern" <<<"$out"; then echo "ok   $name"
  else echo "FAIL $name: exit $rc (want $want)"; sed 's/^/  /' <<<"$out"; fail=1; fi
}

junit "$work/clean.xml" "Codec.Works|run|[  PASSED  ] 1 test." \
  "script.a|run|ok   all good\n  cases skipped as known crash/hang: 0"
expect "a clean run reports no skip" 0 true "no test skipped" "$work/clean.xml"

junit "$work/kernel.xml" \
  "Net.Ring|notrun|x.cpp:12: Skipped\nio_uring is not available\n" "script.a|run|ok   fine"
expect "a kernel feature the machine lacks is listed, and allowed under CI" 0 true \
  "Net.Ring \(skipped\): io_uring is not available$" "$work/kernel.xml"

junit "$work/missing.xml" "script.serial_mbpoll|notrun|skip: mbpoll not installed" \
  "script.fuzz_peers|run|ok   one\npymodbus not available: skipped that peer\nok   two"
expect "missing programs are listed without CI" 0 false \
  "script.fuzz_peers \(skipped in part\): pymodbus not available: skipped that peer  NOT ALLOWED" \
  "$work/missing.xml"
expect "a missing program fails under CI" 1 true "script.serial_mbpoll \(skipped\): skip: mbpoll" \
  "$work/missing.xml"
exit $fail
