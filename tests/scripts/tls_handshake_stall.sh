#!/usr/bin/env bash
# A TLS handshake that stops half-way (a slowloris on port 802) holds a TLS session on the
# slave: `mbstorm serve --transport tls` closes it after --frame-timeout, like a frame that
# stops half-way, and keeps serving everyone else meanwhile. It also says how TLS records are
# encrypted (the kernel TLS offload probe).
#   bash tls_handshake_stall.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
source "$scripts/lib/peer.bash"
source "$scripts/lib/tls_certs.bash"
tls_prologue
trap 'exec 3>&- 2>/dev/null; stop_server; rm -rf "$work"' EXIT  # and the stalled client's socket
start_mbstorm_serve "$work/serve.out" "$mbstorm" "${tls[@]}" --tls-cert "$work/server.pem" \
  --tls-key "$work/server.key" --frame-timeout 500ms --threads 1 -d 30 ||
  { echo "FAIL: serve did not start"; cat "$work/serve.out"*; exit 1; }
fail=0

# The first five bytes of a ClientHello record that announces 512 bytes, then nothing.
exec 3<>"/dev/tcp/127.0.0.1/$port"
printf '\x16\x03\x01\x02\x00' >&3
started=$SECONDS
# Meanwhile a well-behaved client is served.
if timeout -k 5 20 "$mbstorm" read "${tls[@]}" --tls-cert "$work/operator.pem" \
     --tls-key "$work/operator.key" --target "127.0.0.1:$port" --addr 40001 >"$work/read.out" 2>&1
then echo "ok   a client is served while a handshake stalls"
else echo "FAIL: read during the stalled handshake"; cat "$work/read.out"; fail=1; fi
# EOF (the slave closed it) within a few seconds; `timeout` would end with 124.
if timeout 5 cat <&3 >/dev/null; then
  echo "ok   the stalled handshake was closed after $((SECONDS - started)) s"
else echo "FAIL: the stalled handshake was still open after 5 s"; fail=1; fi
exec 3>&-

kill -INT "$server_pid"; wait "$server_pid" 2>/dev/null; server_pid=""
if grep -q "1 closed for a slow frame" "$work/serve.out" "$work/serve.out.err"; then
  echo "ok   counted as a slow frame"
else echo "FAIL: serve's summary does not count it"; cat "$work/serve.out"*; fail=1; fi
# serve says how TLS records are encrypted (userspace OpenSSL; kernel offload probed).
if grep -q "TLS records encrypted by OpenSSL in userspace" "$work/serve.out"; then
  echo "ok   serve names the TLS path: $(grep -o 'over io_uring.*' "$work/serve.out")"
else echo "FAIL: serve does not say how TLS is done"; cat "$work/serve.out"; fail=1; fi
exit $fail
