#!/usr/bin/env bash
# Builds and runs every test: release tests, the Debian package (built from the release build,
# installed, tried and removed), ASan+UBSan tests, each libFuzzer harness for a bounded time
# from its seed corpus, and the benchmarks in smoke mode (no timing assertions). After each
# test stage it lists the tests that skipped, whole or in part, and why; under CI=true a skip
# for anything but what scripts/allowed-skips.txt lists (a missing program or module) fails.
set -euo pipefail
cd "$(dirname "$0")/.."

fuzz_seconds=${MBSTORM_FUZZ_SECONDS:-2}
jobs=${MBSTORM_JOBS:-$(nproc)}
# The suites spend about two fifths of their time waiting (on servers, peers, timeouts), so
# they run two per core: on 2 cores the release suite took 227 s with 2 at once, 170 s with 3
# and 140 s with 4 (2026-11-25), every test passing each time.
test_jobs=${MBSTORM_TEST_JOBS:-$((2 * jobs))}
step() { printf '\n=== %s (%ss elapsed)\n' "$*" "$SECONDS"; }

step "release build + tests"
cmake --preset release >/dev/null
cmake --build --preset release -j "$jobs"
ctest --preset release -j "$test_jobs" --output-junit "$PWD/build/release/junit.xml"
/usr/bin/python3 scripts/skip_report.py build/release/junit.xml "release tests"

step "debian package: build, install, try, remove"
bash scripts/deb-check.sh build/release

step "asan+ubsan build + tests"
cmake --preset asan >/dev/null
cmake --build --preset asan -j "$jobs"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --preset asan -j "$test_jobs" --output-junit "$PWD/build/asan/junit.xml"
/usr/bin/python3 scripts/skip_report.py build/asan/junit.xml "asan+ubsan tests"

step "fuzz harnesses (${fuzz_seconds}s each)"
bash scripts/run-fuzz.sh "$fuzz_seconds"

step "benchmark smoke run"
bash scripts/bench-smoke.sh

step "all tests passed"
