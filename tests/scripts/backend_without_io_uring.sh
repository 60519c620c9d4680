#!/usr/bin/env bash
# Where io_uring is refused (a seccomp filter as Docker 25+'s and containerd 2.0's default
# profiles set, made here by tests/tools/deny_io_uring), `run` and `serve` run on epoll by
# themselves and say why; `--backend io_uring` exits 2 naming the cause. Where io_uring may be
# used, auto picks it and says so.
#   bash backend_without_io_uring.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
deny="$(cd "$(dirname "$mbstorm")" && pwd)/tests/deny_io_uring"
[ -x "$deny" ] || { echo "missing $deny"; exit 1; }
work=$(mktemp -d)
serve_pid=""
trap '[ -n "$serve_pid" ] && kill "$serve_pid" 2>/dev/null; rm -rf "$work"' EXIT
fail=0
check() {  # check NAME COMMAND...: prints ok/FAIL, counts failures
  local name=$1; shift
  if "$@"; then echo "ok   $name"; else echo "FAIL $name"; fail=1; fi
}
json_backend() { /usr/bin/python3 -c 'import json,sys;print(json.load(open(sys.argv[1]))["run"]["backend"])' "$1"; }

# The filter works: a process under it cannot set up a ring (mbstorm --version says so).
"$deny" "$mbstorm" --version >"$work/version" 2>&1
check "under the filter io_uring is unavailable" grep -q 'unavailable' "$work/version"
check "--version names the epoll backend and why" \
  grep -q '^backend: epoll (io_uring_setup refused (Operation not permitted): a seccomp profile' "$work/version"

# run, auto: epoll, said on the start-up lines, in the report and in the JSON; it measures.
"$deny" "$mbstorm" run -d 1s -q --json "$work/auto.json" >"$work/auto.out" 2>"$work/auto.err"
code=$?
check "run under the filter exits 0 (exit $code)" [ "$code" = 0 ]
check "run says it falls back and why" \
  grep -q '^mbstorm run: backend: epoll; io_uring_setup refused (Operation not permitted): a seccomp profile' "$work/auto.err"
check "the report names epoll" grep -q '^  threads [0-9]*, connections 16, depth 16, epoll,' "$work/auto.out"
check "the JSON names epoll" [ "$(json_backend "$work/auto.json")" = epoll ]
ok=$(/usr/bin/python3 -c 'import json,sys;print(json.load(open(sys.argv[1]))["totals"]["ok"])' "$work/auto.json")
check "run on epoll completed transactions ($ok)" [ "${ok:-0}" -gt 1000 ]

# run --backend io_uring: refused before anything starts, naming the cause.
"$deny" "$mbstorm" run -d 1s -q --backend io_uring >"$work/forced.out" 2>&1
code=$?
check "run --backend io_uring under the filter exits 2 (exit $code)" [ "$code" = 2 ]
check "and names the cause" grep -q 'mbstorm run: --backend io_uring: io_uring_setup refused (Operation not permitted)' "$work/forced.out"

# serve, auto: epoll on its start-up line, serving a run that is not filtered.
"$deny" "$mbstorm" serve --listen 127.0.0.1:0 --threads 1 -d 20s >"$work/serve.out" 2>&1 &
serve_pid=$!
for _ in $(seq 100); do grep -q 'listening on' "$work/serve.out" && break; sleep 0.05; done
port=$(sed -n 's/.*listening on 127\.0\.0\.1:\([0-9]*\) .*/\1/p' "$work/serve.out")
check "serve's start-up line names epoll" grep -q 'listening on 127.0.0.1:[0-9]* (tcp, 1 thread, epoll,' "$work/serve.out"
check "serve says why" grep -q '^mbstorm serve: backend: epoll; io_uring_setup refused' "$work/serve.out"
"$mbstorm" run --target "127.0.0.1:${port:-1}" -d 1s -c 4 -q --json "$work/against.json" >/dev/null 2>&1
check "an unfiltered run against it succeeds" [ $? = 0 ]
kill "$serve_pid" 2>/dev/null; wait "$serve_pid" 2>/dev/null; serve_pid=""

"$deny" "$mbstorm" serve --listen 127.0.0.1:0 --backend io_uring -d 1s >"$work/serve_forced.out" 2>&1
code=$?
check "serve --backend io_uring under the filter exits 2 (exit $code)" [ "$code" = 2 ]
check "and names the cause" grep -q 'mbstorm serve: --backend io_uring: io_uring_setup refused' "$work/serve_forced.out"

# Without the filter, on this machine io_uring runs (its features line says so) and auto says it.
if ! grep -q unavailable <("$mbstorm" --version); then
  "$mbstorm" run -d 1s -q --json "$work/free.json" >/dev/null 2>"$work/free.err"
  check "unfiltered, auto picks io_uring and says so" grep -q '^mbstorm run: backend: io_uring$' "$work/free.err"
  check "unfiltered, the JSON names io_uring" [ "$(json_backend "$work/free.json")" = io_uring ]
fi
exit $fail
