#!/usr/bin/env bash
# --metrics-listen under attack (issue #31 item 1): `mbstorm serve -d SECONDS` with its metrics
# endpoint held by SILENT sockets that never send a byte and one client dripping a request head
# a byte every 500 ms. Prints how long a scrape (curl) takes meanwhile, and how long after its
# -d the server exits (the dripper would go on for 50 s).
#   bash bench/run_metrics_attack.sh <build-dir> [SILENT] [SECONDS]
set -euo pipefail
build=${1:?build dir}
silent=${2:-10}
seconds=${3:-5}
mbstorm="$build/mbstorm"
port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
start=$(date +%s.%N)
"$mbstorm" serve --listen 127.0.0.1:0 --metrics-listen "127.0.0.1:$port" -d "$seconds" >/dev/null 2>&1 &
serve=$!
sleep 0.5
/usr/bin/python3 - "$port" "$silent" <<'PY'
import socket, subprocess, sys, threading, time
port, silent = int(sys.argv[1]), int(sys.argv[2])
crowd = [socket.create_connection(("127.0.0.1", port)) for _ in range(silent)]
drip = socket.create_connection(("127.0.0.1", port))
def dripping():
    try:
        for _ in range(100):
            drip.send(b"G")
            time.sleep(0.5)
    except OSError:
        pass
threading.Thread(target=dripping, daemon=True).start()
time.sleep(0.2)
t = time.time()
code = subprocess.run(["curl", "-s", "-m", "30", "-o", "/dev/null", "-w", "%{http_code}",
                       f"http://127.0.0.1:{port}/metrics"], capture_output=True, text=True).stdout
print(f"scrape beside {silent} silent sockets and a dripping client: HTTP {code} in "
      f"{(time.time() - t) * 1000:.1f} ms")
PY
wait "$serve"
end=$(date +%s.%N)
echo "serve -d ${seconds}s exited $(echo "$end - $start - $seconds" | bc) s after its duration (the dripper meant to go on for 50 s)"
