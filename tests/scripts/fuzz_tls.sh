#!/usr/bin/env bash
# `mbstorm fuzz` and `replay` over --transport tls (Modbus/TCP Security), with a CA and
# certificates the test makes with openssl:
#  - `mbstorm serve --transport tls` fuzzed for a few seconds: no findings;
#  - pymodbus 3.0's TLS server (bench/peers/pymodbus_server.py --tls, SOCKET framer) fuzzed:
#    whatever it finds is reported with a reproducer, and `replay --transport tls` reproduces
#    it (findings against pymodbus are pymodbus's, not this test's failures);
#  - a device whose TLS port serves plain Modbus/TCP too: a finding replay reproduces;
#  - a client certificate the server refuses: fuzz stops at discovery and says why;
#  - serve's listening line names the transport, and its /metrics counts TLS handshakes,
#    resumptions (fuzz --tls-resume), refusals and role refusals.
#   bash fuzz_tls.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
source "$scripts/lib/peer.bash"
source "$scripts/lib/tls_certs.bash"
tls_prologue
operator=("${tls[@]}" --tls-cert "$work/operator.pem" --tls-key "$work/operator.key")
fail=0

# 1. The reference slave over TLS: nothing to find, the plaintext cases included. The device
# file's role rules: Operator may use every function code, the Viewer only 1-4. /metrics
# counts the TLS side of it all.
sample() { awk -v key="$2" 'index($0, key " ") == 1 { print $2 }' "$1"; }
printf 'tls_roles:\n  Operator: "1-255"\n  Viewer: [1, 2, 3, 4]\n' >"$work/device.yaml"
if start_mbstorm_serve "$work/serve.out" "$mbstorm" "${tls[@]}" --tls-cert "$work/server.pem" \
     --tls-key "$work/server.key" --threads 1 -d 60 --device "$work/device.yaml" \
     --metrics-listen 127.0.0.1:0; then
  if grep -q "listening on 127.0.0.1:$port (tls, " "$work/serve.out"; then
    echo "ok   serve's listening line names the transport"
  else echo "FAIL serve's listening line: $(cat "$work/serve.out")"; fail=1; fi
  out=$(timeout -k 5 30 "$mbstorm" fuzz --target "127.0.0.1:$port" "${operator[@]}" --tls-resume \
        --seconds 3 --seed 5 -q --out "$work/clean" --json "$work/clean.json" 2>&1); rc=$?
  read -r cases plaintext < <(/usr/bin/python3 -c '
import json, sys
r = json.load(open(sys.argv[1])); by = r["cases_by_class"]
print(r["cases"], by.get("plaintext-to-tls", 0) + by.get("plaintext-in-tls-session", 0))' \
    "$work/clean.json" 2>/dev/null)
  if [ "$rc" = 0 ] && [[ "$out" == *"no findings"* ]] && [ "${cases:-0}" -gt 100 ] &&
     [ "${plaintext:-0}" -gt 0 ]; then
    echo "ok   fuzz mbstorm serve --transport tls: $cases cases ($plaintext plaintext to the TLS port), no findings"
  else
    echo "FAIL fuzz mbstorm serve --transport tls: exit $rc"; sed 's/^/  /' <<<"$out" | head -40
    fail=1
  fi
  # A certificate from another CA: discovery fails, and the reason is the TLS refusal.
  out=$(timeout -k 5 30 "$mbstorm" fuzz --target "127.0.0.1:$port" "${tls[@]}" \
        --tls-cert "$work/rogue.pem" --tls-key "$work/rogue.key" --seconds 2 -q 2>&1); rc=$?
  if [ "$rc" = 2 ] && [[ "$out" == *"TLS session refused"*"alert"* ]]; then
    echo "ok   a refused client certificate stops fuzz with the reason"
  else
    echo "FAIL rogue certificate: exit $rc"; sed 's/^/  /' <<<"$out" | head; fail=1
  fi
  # The Viewer's write: one role refusal more (the fuzzer's function code 0 is outside 1-255,
  # so Operator's cases were refused some too).
  if wait_for 's/.*metrics on \(http:[^ ]*\).*/\1/p' "$work/serve.out.err" &&
     curl -s -o "$work/before.prom" "$found" &&
     { "$mbstorm" write "${tls[@]}" --tls-cert "$work/viewer.pem" \
         --tls-key "$work/viewer.key" --target "127.0.0.1:$port" --addr 40001 7 >/dev/null 2>&1
       curl -s -o "$work/tls.prom" "$found"; }; then
    handshakes=$(sample "$work/tls.prom" mbstorm_slave_tls_handshakes_total)
    resumed=$(sample "$work/tls.prom" mbstorm_slave_tls_resumptions_total)
    failures=$(sample "$work/tls.prom" mbstorm_slave_tls_handshake_failures_total)
    denied=$(( $(sample "$work/tls.prom" mbstorm_slave_tls_role_refusals_total) -
               $(sample "$work/before.prom" mbstorm_slave_tls_role_refusals_total) ))
    if [ "${handshakes:-0}" -gt 10 ] && [ "${resumed:-0}" -gt 0 ] && [ "${failures:-0}" -ge 1 ] &&
       [ "${denied:-0}" = 1 ]; then
      echo "ok   /metrics: $handshakes TLS handshakes, $resumed resumed (fuzz --tls-resume), $failures refused, $denied role refusal (device file's tls_roles)"
    else
      echo "FAIL /metrics TLS counters: handshakes $handshakes, resumed $resumed, failures $failures, role refusals $denied"
      grep tls "$work/tls.prom" | sed 's/^/  /'; fail=1
    fi
  else
    echo "FAIL serve's /metrics could not be read"; fail=1
  fi
else
  echo "FAIL: mbstorm serve --transport tls did not start"; cat "$work/serve.out.err"; fail=1
fi
stop_server

# 2. A device whose TLS port also serves plain Modbus/TCP (tls_plaintext_too_server.py): the
# plaintext case is a finding, and replay reproduces it.
start_server "$work/dual.out" /usr/bin/python3 "$scripts/tls_plaintext_too_server.py" "$work" ||
  { echo "FAIL: the plaintext-too server did not start"; exit 1; }
out=$(timeout -k 5 30 "$mbstorm" fuzz --target "127.0.0.1:$port" "${operator[@]}" --seconds 3 \
      -q --max-connections 16 --out "$work/dual" 2>&1); rc=$?
found_dir=("$work"/dual/*tls-port-answers-plaintext*/)
if [ "$rc" = 1 ] && [ -d "${found_dir[0]}" ]; then
  again=$("$mbstorm" replay "${found_dir[0]}" --target "127.0.0.1:$port" "${operator[@]}" 2>&1)
  rrc=$?
  if [ "$rrc" = 1 ] && [[ "$again" == *"REPRODUCES: the TLS port answered plain Modbus/TCP"* ]]; then
    echo "ok   a TLS port that serves plaintext is a finding, and replay reproduces it"
  else
    echo "FAIL replay of the plaintext finding: exit $rrc"; sed 's/^/  /' <<<"$again" | head; fail=1
  fi
else
  echo "FAIL the plaintext-too server: exit $rc, no tls-port-answers-plaintext finding"
  sed 's/^/  /' <<<"$out" | head -30; fail=1
fi
stop_server

# 3. pymodbus's TLS server: findings come with reproducers that replay reproduces over TLS.
if ! /usr/bin/python3 -c 'import pymodbus.server' 2>/dev/null; then
  echo "skip: pymodbus not installed"; exit $((fail ? 1 : 77))
fi
start_server "$work/py.out" /usr/bin/python3 "$scripts/../../bench/peers/pymodbus_server.py" \
  --tls "$work" --seconds 60 || { echo "FAIL: pymodbus TLS server did not start"; exit 1; }
out=$(timeout -k 5 40 "$mbstorm" fuzz --target "127.0.0.1:$port" "${operator[@]}" --seconds 3 \
      --seed 5 -q --max-connections 64 --out "$work/py" 2>&1); rc=$?
if [ "$rc" != 0 ] && [ "$rc" != 1 ]; then
  echo "FAIL fuzz pymodbus over TLS: exit $rc"; sed 's/^/  /' <<<"$out" | head -40; fail=1
elif [ "$rc" = 0 ]; then
  # pymodbus answers frames with protocol id != 0 over any transport (found in the first
  # looks): no finding is a fuzzer that no longer judges answers over TLS.
  echo "FAIL fuzz pymodbus over TLS: no findings"; sed 's/^/  /' <<<"$out" | head -20; fail=1
elif ! compgen -G "$work/py/*-spec-deviation-answers-nonzero-protocol-id" >/dev/null; then
  # pymodbus 3.0 never checks the protocol id (bench/README.md's triage); the first looks show
  # it within the first second on every transport.
  echo "FAIL fuzz pymodbus over TLS: answers-nonzero-protocol-id not found"
  sed 's/^/  /' <<<"$out" | head -20; fail=1
else
  # A spec deviation replays deterministically; else the first finding.
  folders=("$work"/py/*/)
  deviations=("$work"/py/*spec-deviation*/)
  finding=${folders[0]}
  [ -d "${deviations[0]}" ] && finding=${deviations[0]}
  name=${finding%/}; name=${name##*/}
  again=$("$mbstorm" replay "$finding" --target "127.0.0.1:$port" \
          "${operator[@]}" 2>&1); rrc=$?
  if [ "$rrc" = 1 ] && [[ "$again" == *"REPRODUCES"* ]]; then
    echo "ok   fuzz pymodbus over TLS: ${#folders[@]} finding(s); replay over TLS reproduces $name"
  else
    echo "FAIL replay of $name over TLS: exit $rrc"; sed 's/^/  /' <<<"$again" | head -20; fail=1
  fi
  # The same finding over plain TCP cannot reach the TLS port.
  again=$("$mbstorm" replay "$finding" --target "127.0.0.1:$port" \
          --timeout 500ms 2>&1); rrc=$?
  if [ "$rrc" != 1 ]; then echo "ok   replay without --transport tls does not reproduce"
  else echo "FAIL replay over plain TCP reproduced"; sed 's/^/  /' <<<"$again" | head; fail=1; fi
fi
exit $fail
