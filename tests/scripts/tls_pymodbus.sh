#!/usr/bin/env bash
# Interop for --transport tls (Modbus/TCP Security) against pymodbus 3.0 (Debian,
# /usr/bin/python3), with a CA and certificates the test makes with openssl:
#  - pymodbus's TLS client against `mbstorm serve --transport tls` (tls_pymodbus_client.py:
#    TLS 1.2 and 1.3, the role allow-list's exception 01, refused certificates);
#  - `mbstorm run --transport tls` against pymodbus's TLS server, with and without
#    --tls-resume: every transaction answered, handshakes counted, resumptions seen;
#  - `mbstorm read`/`write --transport tls` against both.
#   bash tls_pymodbus.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
source "$scripts/lib/peer.bash"
source "$scripts/lib/tls_certs.bash"
if ! /usr/bin/python3 -c 'import pymodbus.client, pymodbus.server' 2>/dev/null; then
  echo "skip: pymodbus not installed"; exit 77
fi
tls_prologue
fail=0
# expect <name> <wanted exit code> <wanted text> <mbstorm args...>
expect() {
  local name=$1 code=$2 text=$3; shift 3
  local out rc
  out=$(timeout -k 5 30 "$mbstorm" "$@" 2>&1); rc=$?
  if [ "$rc" = "$code" ] && [[ "$out" == *"$text"* ]]; then echo "ok   $name"
  else echo "FAIL $name: exit $rc, wanted $code and '$text'"; sed 's/^/  /' <<<"$out"; fail=1; fi
}
# json_counts FILE: transactions, errors, TLS handshakes and resumptions of a run's --json.
json_counts() {
  /usr/bin/python3 -c '
import json, sys
r = json.load(open(sys.argv[1])); c = r["connections"]
print(r["totals"]["transactions"], r["totals"]["errors"], c["tls_handshakes"], c["tls_resumed"])' \
    "$1" 2>/dev/null
}

# 1. pymodbus client -> mbstorm serve.
"$mbstorm" serve "${tls[@]}" --tls-cert "$work/server.pem" --tls-key "$work/server.key" \
  --tls-role Operator=1-6,15,16 --tls-role Viewer=1-4 --listen 127.0.0.1:0 --threads 1 -d 60 \
  >"$work/serve.out" 2>&1 &
server_pid=$!
if wait_for 's/.*listening on 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$work/serve.out"; then
  timeout -k 5 60 /usr/bin/python3 "$scripts/tls_pymodbus_client.py" "$found" "$work" || fail=1
  # mbstorm's own one-shot client: the Viewer's write is exception 01, its read is allowed.
  viewer=("${tls[@]}" --tls-cert "$work/viewer.pem" --tls-key "$work/viewer.key")
  expect "read as Viewer" 0 "[0]: 0" read "${viewer[@]}" --target "127.0.0.1:$found" --addr 40001
  expect "write as Viewer refused" 1 "ILLEGAL FUNCTION" write "${viewer[@]}" \
    --target "127.0.0.1:$found" --addr 40001 7
else
  echo "FAIL: mbstorm serve --transport tls did not start"; cat "$work/serve.out"; fail=1
fi
stop_server

# 2. mbstorm run -> pymodbus TLS server.
start_server "$work/py.out" /usr/bin/python3 "$scripts/../../bench/peers/pymodbus_server.py" \
  --tls "$work" --seconds 60 || { echo "FAIL: pymodbus TLS server did not start"; exit 1; }
client=("${tls[@]}" --tls-cert "$work/operator.pem" --tls-key "$work/operator.key")
expect "write to pymodbus" 0 "wrote 2 register(s)" write "${client[@]}" \
  --target "127.0.0.1:$port" --addr 40021 1234 5678
expect "read back from pymodbus" 0 $'[20]: 1234\n[21]: 5678' read "${client[@]}" \
  --target "127.0.0.1:$port" --addr 40021 --quantity 2
for resume in "" --tls-resume; do
  out=$(timeout -k 5 60 "$mbstorm" run --target "127.0.0.1:$port" "${client[@]}" $resume \
        -c 4 --depth 1 -d 1s --warmup 0 --fc 3 --addr 0 --quantity 10 --json "$work/run.json" 2>&1)
  rc=$?
  read -r completed errors handshakes resumed < <(json_counts "$work/run.json")
  if [ "$rc" = 0 ] && [ "${completed:-0}" -gt 0 ] && [ "${errors:-1}" = 0 ] &&
     [ "${handshakes:-0}" -ge 4 ]; then
    echo "ok   run ${resume:-(full handshakes)} against pymodbus: $completed answered, $handshakes handshakes"
  else
    echo "FAIL run $resume against pymodbus: exit $rc"; sed 's/^/  /' <<<"$out" | head -40; fail=1
  fi
done

# 3. A client certificate the server's CA did not sign: nothing is answered (pymodbus closes
# without an alert, so the run cannot tell a refusal from a drop, and says it may be one; see
# part 4 for the alert).
out=$(timeout -k 5 30 "$mbstorm" run --target "127.0.0.1:$port" "${tls[@]}" \
      --tls-cert "$work/rogue.pem" --tls-key "$work/rogue.key" -c 1 -d 1s \
      --json "$work/rogue.json" 2>&1); rc=$?
read -r completed errors handshakes resumed < <(json_counts "$work/rogue.json")
if [ "$rc" != 0 ] && [ "${completed:-1}" = "${errors:-0}" ] &&
   [[ "$out" == *"may refuse the client certificate"* ]]; then
  echo "ok   rogue client gets no answer from pymodbus, and is told why it may be"
else echo "FAIL rogue client against pymodbus: exit $rc"; sed 's/^/  /' <<<"$out" | head; fail=1; fi
stop_server

# 4. --tls-resume against mbstorm serve, which drops a share of its connections: the
# reconnections resume their sessions (TLS 1.3 tickets), and without the flag none does.
"$mbstorm" serve "${tls[@]}" --tls-cert "$work/server.pem" --tls-key "$work/server.key" \
  --listen 127.0.0.1:0 --threads 1 -d 60 --drop-rate 0.02 --seed 7 >"$work/serve2.out" 2>&1 &
server_pid=$!
if wait_for 's/.*listening on 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$work/serve2.out"; then
  for resume in --tls-resume ""; do
    timeout -k 5 60 "$mbstorm" run --target "127.0.0.1:$found" "${client[@]}" $resume -c 2 \
      --depth 1 -d 1s --warmup 0 --json "$work/resume.json" >/dev/null 2>&1
    read -r completed errors handshakes resumed < <(json_counts "$work/resume.json")
    if [ -n "$resume" ] && [ "${handshakes:-0}" -gt 2 ] && [ "${resumed:-0}" -gt 0 ]; then
      echo "ok   --tls-resume: $resumed of $handshakes handshakes resumed"
    elif [ -z "$resume" ] && [ "${handshakes:-0}" -gt 2 ] && [ "${resumed:-1}" = 0 ]; then
      echo "ok   no --tls-resume: none of $handshakes handshakes resumed"
    else
      echo "FAIL ${resume:-no resume}: $handshakes handshakes, $resumed resumed"; fail=1
    fi
  done
  # mbstorm serve sends the alert: the run stops at once and says why.
  out=$(timeout -k 5 30 "$mbstorm" run --target "127.0.0.1:$found" "${tls[@]}" \
        --tls-cert "$work/rogue.pem" --tls-key "$work/rogue.key" -c 1 -d 5s 2>&1); rc=$?
  if [ "$rc" != 0 ] && [[ "$out" == *"TLS session refused"* ]]; then
    echo "ok   rogue client refused with the server's alert"
  else echo "FAIL rogue client against mbstorm serve: exit $rc"; sed 's/^/  /' <<<"$out" | head; fail=1; fi
else
  echo "FAIL: mbstorm serve --transport tls did not start"; fail=1
fi
stop_server

# 5. A peer that accepts the TCP connection and never answers the ClientHello: the handshake
# fails at the connect timeout instead of hanging the connection.
start_server "$work/silent.out" /usr/bin/python3 -c '
import socket, time
s = socket.socket(); s.bind(("127.0.0.1", 0)); s.listen(16)
print("PORT", s.getsockname()[1], flush=True)
held = []
while True:
    held.append(s.accept()[0])' || { echo "FAIL: silent listener did not start"; exit 1; }
out=$(timeout -k 5 30 "$mbstorm" run --target "127.0.0.1:$port" "${client[@]}" -c 1 -d 5s \
      --connect-timeout 300ms 2>&1); rc=$?
if [ "$rc" != 0 ] && [[ "$out" == *"no handshake within the connect timeout"* ]]; then
  echo "ok   a silent peer fails the handshake at the connect timeout"
else echo "FAIL silent peer: exit $rc"; sed 's/^/  /' <<<"$out" | head; fail=1; fi
exit $fail
