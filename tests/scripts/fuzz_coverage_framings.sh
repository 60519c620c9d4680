#!/usr/bin/env bash
# mbstorm fuzz --coverage (issue #27) on targets that do not speak MBAP: the C device of
# tests/tools/coverage_device.c built with clang -fsanitize-coverage=trace-pc-guard,trace-cmp
# and mbstorm's runtime, speaking RTU over TCP (a gateway's framing), then RTU and ASCII on a
# serial line (a socat pty pair; mbstorm starts the device on the other end). The coverage
# mutations change a frame's unit and PDU and frame it again (CRC, LRC). In every framing both
# planted crashes, each needing two fields equal to constants at once, must be found, each once
# and nothing else, with edges that only grow and a corpus of frames in the target's own
# framing; over TCP the reproducer must crash the device again when replayed alone.
#   bash fuzz_coverage_framings.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=${2:-$(cd "$(dirname "$0")" && pwd)}
root=$(cd "$scripts/../.." && pwd)
source "$scripts/lib/peer.bash"
source "$scripts/lib/serial.bash"
serial_prologue

# bounded SECONDS COMMAND...: COMMAND, killed if it outlives SECONDS.
bounded() { timeout -k 5 "$@"; }

fail=0
clang -O1 -fsanitize-coverage=trace-pc-guard,trace-cmp -c "$root/tests/tools/coverage_device.c" \
  -o "$work/device.o" &&
  clang -O1 -c "$root/coverage/mbstorm_coverage.c" -o "$work/runtime.o" &&
  clang "$work/device.o" "$work/runtime.o" -o "$work/device" ||
  { echo "FAIL: the device does not build with clang and the coverage runtime"; exit 1; }
free_port() { /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }

# fuzz NAME SECONDS FLAGS...: a coverage run that ends at the second planted crash.
fuzz() {
  local name=$1 seconds=$2; shift 2
  bounded $((seconds + 60)) "$mbstorm" fuzz "$@" --coverage --seconds "$seconds" --seed 1 -q \
    --no-model --max-connections 0 --max-findings 2 --corpus "$work/$name-corpus" \
    --out "$work/$name" --json "$work/$name.json" >"$work/$name.log" 2>&1
  local rc=$?
  if [ "$rc" -ne 0 ] && [ "$rc" -ne 1 ]; then
    echo "FAIL $name: exit $rc"; sed 's/^/  /' "$work/$name.log" | tail -20; fail=1
  fi
}

# check NAME FRAMING [PLANTED]: edges growing, a corpus in FRAMING, and with PLANTED both planted
# crashes, each once, nothing else.
check() {
  /usr/bin/python3 - "$work/$1.json" "$work/$1-corpus" "$2" "$1" "${3:-}" <<'PY'
import glob, json, sys
path, corpus, framing, name, planted_too = sys.argv[1:6]
planted = {"crash:target-down/fc06", "crash:target-down/fc16"}
j = json.load(open(path))
found = [f["root_cause"] for f in j["findings"]]
cov = j["coverage"]
over_time = [e for _, e in cov["edges_over_time"]]
frames = [bytes.fromhex(s["hex"]) for f in glob.glob(corpus + "/*.json")
          for s in json.load(open(f))["steps"] if s["op"] == "send"]
# RTU: a CRC that holds (a mutated frame is made again around its PDU); ASCII: ':' .. CR LF.
# Transport cases (bad checksums, pieces) are in the corpus too: most sends, not all.
def crc16(b):
    c = 0xFFFF
    for x in b:
        c ^= x
        for _ in range(8):
            c = (c >> 1) ^ 0xA001 if c & 1 else c >> 1
    return c
def framed(b):
    if framing == "ascii":
        return b[:1] == b":" and b[-2:] == b"\r\n"
    return len(b) >= 4 and crc16(b[:-2]) == b[-2] | b[-1] << 8
def mbap(b):
    return len(b) >= 8 and b[2:4] == b"\0\0" and int.from_bytes(b[4:6], "big") + 6 == len(b)
checks = [
    (sorted(found) == sorted(planted) or not planted_too,
     f"{name}: both planted crashes, each once, nothing else (found {found}) in "
     f"{j['seconds']:.1f} s, {j['cases']} cases" if planted_too else
     f"{name}: {j['cases']} cases in {j['seconds']:.1f} s (found {found})"),
    (over_time == sorted(over_time) and cov["edges"] > 20 and cov["corpus"] > 5,
     f"{name}: {cov['edges']} edges, only growing; corpus {cov['corpus']}"),
    (frames and sum(map(framed, frames)) >= 0.75 * len(frames) and not any(map(mbap, frames)),
     f"{name}: the corpus holds {framing} frames ({sum(map(framed, frames))} of {len(frames)} "
     f"sends; {sum(map(mbap, frames))} MBAP frames)"),
]
for ok, what in checks:
    print(("ok   " if ok else "FAIL ") + what)
sys.exit(0 if all(ok for ok, _ in checks) else 1)
PY
}

p=$(free_port)
fuzz rtu-over-tcp 60 --transport rtu-over-tcp --target "127.0.0.1:$p" \
  --target-cmd "exec $work/device --port $p --framing rtu"
check rtu-over-tcp rtu planted || fail=1
folder=$(compgen -G "$work/rtu-over-tcp/*-crash-target-down-fc06" | head -1)
if [ -n "$folder" ] && start_server "$work/replay.out" "$work/device" --port 0 --framing rtu; then
  out=$(bounded 30 "$mbstorm" replay "$folder" --transport rtu-over-tcp --target "127.0.0.1:$port" --runs 1 2>&1)
  if [ $? -eq 1 ] && grep -q "1 of 1 run(s) reproduced" <<<"$out"; then
    echo "ok   rtu-over-tcp: replay reproduces $(basename "$folder")"
  else
    echo "FAIL rtu-over-tcp: replay of $(basename "$folder")"; sed 's/^/  /' <<<"$out" | tail -5; fail=1
  fi
  stop_server
else
  echo "FAIL rtu-over-tcp: no fc06 crash to replay, or the device did not start"; fail=1
fi

# On a line the device dies silently (no connection to close): mbstorm started it, so its exit
# is the crash (a whole-server hang otherwise). About 20 cases/s there.
for framing in rtu ascii; do
  rm -f "$work/line_a" "$work/line_b"
  start_pty_pair "$work" || { echo "FAIL: socat made no pty pair"; exit 1; }
  fuzz "serial-$framing" 90 --serial "$work/line_b" --framing "$framing" --baud 115200 \
    --parity none --timeout 300ms --target-cmd "exec $work/device --tty $work/line_a --framing $framing"
  check "serial-$framing" "$framing" planted || fail=1
  stop_pty_pair
done
exit $fail
