#!/usr/bin/env bash
# `mbstorm fuzz` and `replay` over --transport tls (Modbus/TCP Security), with a CA and
# certificates the test makes with openssl:
#  - `mbstorm serve --transport tls` fuzzed for a few seconds: no findings;
#  - pymodbus 3.0's TLS server (tests/scripts/tls_pymodbus_server.py, SOCKET framer) fuzzed:
#    whatever it finds is reported with a reproducer, and `replay --transport tls` reproduces
#    it (findings against pymodbus are pymodbus's, not this test's failures);
#  - a client certificate the server refuses: fuzz stops at discovery and says why.
#   bash fuzz_tls.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
source "$scripts/lib/peer.bash"
source "$scripts/lib/tls_certs.bash"
work=$(mktemp -d)
trap 'stop_server; rm -rf "$work"' EXIT

make_tls_certs "$work" || { echo "FAIL: openssl could not make the certificates"; exit 1; }
tls=(--transport tls --tls-ca "$work/ca.pem")
operator=("${tls[@]}" --tls-cert "$work/operator.pem" --tls-key "$work/operator.key")
fail=0

# 1. The reference slave over TLS: nothing to find.
if start_mbstorm_serve "$work/serve.out" "$mbstorm" "${tls[@]}" --tls-cert "$work/server.pem" \
     --tls-key "$work/server.key" -t 1 -d 60; then
  out=$(timeout -k 5 30 "$mbstorm" fuzz --target "127.0.0.1:$port" "${operator[@]}" \
        --seconds 3 --seed 5 -q --out "$work/clean" --json "$work/clean.json" 2>&1); rc=$?
  cases=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["cases"])' \
          "$work/clean.json" 2>/dev/null)
  if [ "$rc" = 0 ] && [[ "$out" == *"no findings"* ]] && [ "${cases:-0}" -gt 100 ]; then
    echo "ok   fuzz mbstorm serve --transport tls: $cases cases, no findings"
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
else
  echo "FAIL: mbstorm serve --transport tls did not start"; cat "$work/serve.out.err"; fail=1
fi
stop_server

# 2. pymodbus's TLS server: findings come with reproducers that replay reproduces over TLS.
if ! /usr/bin/python3 -c 'import pymodbus.server' 2>/dev/null; then
  echo "skip: pymodbus not installed"; exit $((fail ? 1 : 77))
fi
start_server "$work/py.out" /usr/bin/python3 "$scripts/tls_pymodbus_server.py" "$work" \
  --seconds 60 || { echo "FAIL: pymodbus TLS server did not start"; exit 1; }
out=$(timeout -k 5 40 "$mbstorm" fuzz --target "127.0.0.1:$port" "${operator[@]}" --seconds 4 \
      --seed 5 -q --max-connections 64 --out "$work/py" 2>&1); rc=$?
if [ "$rc" != 0 ] && [ "$rc" != 1 ]; then
  echo "FAIL fuzz pymodbus over TLS: exit $rc"; sed 's/^/  /' <<<"$out" | head -40; fail=1
elif [ "$rc" = 0 ]; then
  echo "ok   fuzz pymodbus over TLS: no findings"
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
