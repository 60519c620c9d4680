#!/usr/bin/env bash
# A TLS handshake that stops half-way (a slowloris on port 802) holds a TLS session on the
# slave: `mbstorm serve --transport tls` closes it after --frame-timeout, like a frame that
# stops half-way, and keeps serving everyone else meanwhile. So it does a socket that never
# sends a byte (timed from the accept) and, after a handshake, a record dripped a byte at a
# time; and at its connection limit it evicts connections still in their handshake before
# authenticated sessions (issue #31 item 3). It also says how TLS records are encrypted (the
# kernel TLS offload probe).
#   bash tls_handshake_stall.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
source "$scripts/lib/peer.bash"
source "$scripts/lib/tls_certs.bash"
tls_prologue
trap 'exec 3>&- 2>/dev/null; stop_server; rm -rf "$work"' EXIT  # and the stalled client's socket
start_mbstorm_serve "$work/serve.out" "$mbstorm" "${tls[@]}" --tls-cert "$work/server.pem" \
  --tls-key "$work/server.key" --frame-timeout 500ms --threads 1 -d 90 ||
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

# Python's ssl over a raw socket (MemoryBIO): the handshake done, the socket is ours to misuse.
cat >"$work/tls_attacks.py" <<'PY'
import select, socket, ssl, sys, time
mode, port, work = sys.argv[1], int(sys.argv[2]), sys.argv[3]
ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)
ctx.load_verify_locations(f"{work}/ca.pem")
ctx.load_cert_chain(f"{work}/operator.pem", f"{work}/operator.key")

def session():
    raw = socket.create_connection(("127.0.0.1", port))
    inc, out = ssl.MemoryBIO(), ssl.MemoryBIO()
    tls = ctx.wrap_bio(inc, out, server_hostname="127.0.0.1")
    while True:
        try:
            tls.do_handshake()
            break
        except ssl.SSLWantReadError:
            raw.sendall(out.read())
            data = raw.recv(65536)
            if not data:
                raise SystemExit("closed during the handshake")
            inc.write(data)
    raw.sendall(out.read())
    return raw, tls, inc, out

def closed_within(raw, seconds, drip=b""):
    # Sends `drip` a byte every 200 ms meanwhile; True once the server has closed.
    end, i = time.time() + seconds, 0
    while time.time() < end:
        if select.select([raw], [], [], 0.2)[0]:
            try:
                if not raw.recv(65536):
                    return True
            except ConnectionResetError:
                return True
        if i < len(drip):
            try:
                raw.send(drip[i:i + 1])
            except OSError:
                return True
            i += 1
    return False

def answers(raw, tls, inc, out):
    tls.write(bytes([0, 1, 0, 0, 0, 6, 1, 3, 0, 0, 0, 1]))
    raw.sendall(out.read())
    end = time.time() + 3
    while time.time() < end:
        try:
            return len(tls.read(256)) >= 9
        except ssl.SSLWantReadError:
            if not select.select([raw], [], [], 0.2)[0]:
                continue
            data = raw.recv(65536)
            if not data:
                return False
            inc.write(data)
    return False

if mode == "drip":  # a record header announcing 16 KiB, then a byte every 200 ms for 20 s
    raw, *_ = session()
    print("closed" if closed_within(raw, 20, bytes([0x17, 3, 3, 0x40, 0]) + bytes(95)) else "open")
elif mode == "silent":
    raw = socket.create_connection(("127.0.0.1", port))
    print("closed" if closed_within(raw, 10) else "open")
elif mode == "evict":  # 5 authenticated idle sessions, then 20 sockets that say nothing
    sessions = [session() for _ in range(5)]
    crowd = [socket.create_connection(("127.0.0.1", port)) for _ in range(20)]
    time.sleep(0.5)
    print(sum(answers(*s) for s in sessions), "of 5 sessions still answered")
PY
# (serve runs 90 s: its own end must not pass for these closes.)
silent=$(timeout 40 /usr/bin/python3 "$work/tls_attacks.py" silent "$port" "$work" 2>&1)
[ "$silent" = closed ] && echo "ok   a socket that never sends a byte is closed by --frame-timeout" ||
  { echo "FAIL: a silent socket: $silent"; fail=1; }
dripped=$(timeout 40 /usr/bin/python3 "$work/tls_attacks.py" drip "$port" "$work" 2>&1)
[ "$dripped" = closed ] && echo "ok   a record dripped after the handshake is closed by --frame-timeout" ||
  { echo "FAIL: a record dripped after the handshake: $dripped"; fail=1; }

kill -INT "$server_pid"; wait "$server_pid" 2>/dev/null; server_pid=""
if grep -q "3 closed for a slow frame" "$work/serve.out" "$work/serve.out.err"; then
  echo "ok   counted as slow frames"
else echo "FAIL: serve's summary does not count it"; cat "$work/serve.out"*; fail=1; fi
# serve says how TLS records are encrypted (userspace OpenSSL; kernel offload probed).
if grep -q "TLS records encrypted by OpenSSL in userspace" "$work/serve.out"; then
  echo "ok   serve names the TLS path: $(grep -o 'over io_uring.*' "$work/serve.out")"
else echo "FAIL: serve does not say how TLS is done"; cat "$work/serve.out"; fail=1; fi

# At its limit (6 connections), serve evicts the connections still in their handshake, not
# the authenticated sessions that are merely idle.
start_mbstorm_serve "$work/evict.out" "$mbstorm" "${tls[@]}" --tls-cert "$work/server.pem" \
  --tls-key "$work/server.key" --max-connections 6 --threads 1 -d 30 ||
  { echo "FAIL: serve did not start"; cat "$work/evict.out"*; exit 1; }
kept=$(timeout 40 /usr/bin/python3 "$work/tls_attacks.py" evict "$port" "$work" 2>&1)
[ "$kept" = "5 of 5 sessions still answered" ] && echo "ok   evictions took the handshaking sockets: $kept" ||
  { echo "FAIL: evictions at the limit: $kept"; fail=1; }
exit $fail
