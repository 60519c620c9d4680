#!/usr/bin/env bash
# Output memory after a crowd of slow readers (issue #31 item 5): `mbstorm serve` (one thread)
# gets CLIENTS connections that each ask for about 350 KB of answers and never read, for 3 s;
# then they all close. Prints serve's resident memory before, during and after.
#   bash bench/run_slow_reader_crowd.sh <build-dir> [CLIENTS]
set -euo pipefail
build=${1:?build dir}
clients=${2:-1500}
ulimit -n 20000 2>/dev/null || true
port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
"$build/mbstorm" serve --listen "127.0.0.1:$port" -d 20s --threads 1 >/dev/null 2>&1 &
serve=$!
trap 'kill $serve 2>/dev/null || true' EXIT
sleep 0.5
/usr/bin/python3 - "$port" "$serve" "$clients" <<'PY'
import socket, struct, sys, time
port, pid, clients = int(sys.argv[1]), sys.argv[2], int(sys.argv[3])
def rss():
    for line in open(f"/proc/{pid}/status"):
        if line.startswith("VmRSS"):
            return int(line.split()[1]) // 1024
# 1,400 reads of 125 registers: about 360 KB of answers per connection.
req = b"".join(struct.pack(">HHHBBHH", i, 0, 6, 1, 3, 0, 125) for i in range(1400))
print(f"before the crowd: {rss()} MB")
socks = []
for _ in range(clients):
    s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.connect(("127.0.0.1", port))
    s.setblocking(False)
    try:
        s.send(req)
    except BlockingIOError:
        pass
    socks.append(s)
time.sleep(3)
print(f"{clients} clients not reading, 3 s: {rss()} MB")
for s in socks:
    s.close()
prev = 0
for t in (0.5, 1.5, 3, 5):
    time.sleep(t - prev)
    prev = t
    print(f"{t} s after they left: {rss()} MB")
PY
