#!/usr/bin/env bash
# Grey-box against black-box on libmodbus itself (issue #27): libmodbus built from its source
# as a static library with clang -fsanitize-coverage=trace-pc-guard,trace-cmp,pc-table, a small
# device on it (tests/tools/libmodbus_coverage_device.c: libmodbus's unit-test map, none of it
# at address 0) and mbstorm's runtime. The device is fuzzed for SECONDS twice, same seed, started
# by mbstorm (--target-cmd): black-box (the map is a segment this script hands the device and
# reads afterwards: every cell ever hit, start-up included) and --coverage (mbstorm's count of
# the edges its cases reached; --coverage-report for the functions never reached). Prints the
# edges of each, the start-up's alone, and the functions of modbus.c each run reached.
# Built at -O0, so that --coverage-report sees each function as the source has it (at -O1 a
# static function inlined where it is called is reported never reached).
# Usage: bench/run_libmodbus_coverage.sh LIBMODBUS_SRC BUILD_DIR [SECONDS] [DEVICE_FLAGS...]
#   DEVICE_FLAGS: e.g. --response-timeout-ms 10 (libmodbus's pause after exceptions 01/03).
#   LIBMODBUS_SRC: a libmodbus source tree (git clone https://github.com/stephane/libmodbus; no
#   configure needed: the few settings it makes are written here). No network used.
set -euo pipefail
src=$(cd "${1:?libmodbus source dir}" && pwd)
build=$(cd "${2:?build dir}" && pwd)
secs=${3:-60}
device_flags=("${@:4}")
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# What configure would write for Linux, and the version header from its template.
cat >"$work/config.h" <<'EOF'
#define HAVE_ACCEPT4 1
#define HAVE_GAI_STRERROR 1
#define HAVE_NETINET_IN_H 1
#define HAVE_NETINET_IP_H 1
#define HAVE_DECL_TIOCM_RTS 1
#define HAVE_DECL_TIOCSRS 1
EOF
version() { sed -n "s/^m4_define(\[libmodbus_version_$1\], \[\([0-9]*\)\])/\1/p" "$src/configure.ac"; }
major=$(version major) minor=$(version minor) micro=$(version micro)
sed -e "s/@LIBMODBUS_VERSION_MAJOR@/$major/;s/@LIBMODBUS_VERSION_MINOR@/$minor/" \
  -e "s/@LIBMODBUS_VERSION_MICRO@/$micro/;s/@LIBMODBUS_VERSION@/$major.$minor.$micro/g" \
  "$src/src/modbus-version.h.in" >"$work/modbus-version.h"

flags=(-O0 -g -fsanitize-coverage=trace-pc-guard,trace-cmp,pc-table -D_GNU_SOURCE
  -include "$work/config.h" -I"$work" -I"$src/src")
for f in modbus modbus-data modbus-tcp; do clang "${flags[@]}" -c "$src/src/$f.c" -o "$work/$f.o"; done
ar rcs "$work/libmodbus-coverage.a" "$work/modbus.o" "$work/modbus-data.o" "$work/modbus-tcp.o"
clang -O1 -c "$here/../coverage/mbstorm_coverage.c" -o "$work/runtime.o"
clang "${flags[@]}" "$here/../tests/tools/libmodbus_coverage_device.c" "$work/libmodbus-coverage.a" \
  "$work/runtime.o" -o "$work/device"
echo "libmodbus $major.$minor.$micro ($(git -C "$src" describe --always --tags 2>/dev/null || echo 'no git'))," \
  "$(nm --defined-only "$work/modbus.o" | grep ' [Tt] ' | grep -vc sancov) functions in modbus.o"

# shm create|count|remove: a map segment of our own for the black-box run (AFL's layout: the
# runtime logs comparisons past the map, hence the room after it).
shm() {
  /usr/bin/python3 - "$@" <<'PY'
import ctypes, sys
libc = ctypes.CDLL(None, use_errno=True)
libc.shmat.restype = ctypes.c_void_p
IPC_PRIVATE, IPC_CREAT, IPC_RMID, MAP = 0, 0o1000, 0, 1 << 16
if sys.argv[1] == "create":
    print(libc.shmget(IPC_PRIVATE, MAP + (1 << 15), IPC_CREAT | 0o600))
    sys.exit(0)
shm_id = int(sys.argv[2])
if sys.argv[1] == "remove":
    libc.shmctl(shm_id, IPC_RMID, None)
    sys.exit(0)
cells = ctypes.string_at(libc.shmat(shm_id, None, 0), MAP)
hit = {i for i, b in enumerate(cells) if b}
print(len(hit))
if len(sys.argv) > 3:  # the functions whose entry cell was hit, from the runtime's PC list
    import subprocess
    module, by_module = None, {}
    for line in open(sys.argv[3]):
        word = line.split()
        if word[0] == "module":
            module = word[1]
        elif int(word[1]) in hit:
            by_module.setdefault(module, set()).add(word[0])
    names = set()
    for module, offsets in by_module.items():
        out = subprocess.run(["addr2line", "-f", "-e", module, *sorted(offsets)],
                             capture_output=True, text=True).stdout.split("\n")
        names |= {f"{fn} {where.rsplit('/', 1)[-1].split(':')[0]}" for fn, where in zip(out[::2], out[1::2])}
    with open(sys.argv[4], "w") as f:
        f.write("\n".join(sorted(names)) + "\n")
PY
}

port=$((20000 + RANDOM % 10000))
fuzz() {  # fuzz NAME TARGET_CMD [FLAGS...]
  local name=$1 cmd=$2; shift 2
  "$build/mbstorm" fuzz --target "127.0.0.1:$port" --target-cmd "$cmd" --seconds "$secs" --seed 1 \
    -q --out "$work/out-$name" --json "$work/$name.json" "$@" >"$work/$name.log" 2>&1 || true
}
summary() {  # summary NAME: cases, cases/s, findings
  /usr/bin/python3 - "$work/$1.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
print(f"{j['cases']:,} cases in {j['seconds']:.0f} s ({j['cases_per_second']:,.0f}/s), "
      f"findings: {', '.join(f['root_cause'] for f in j['findings']) or 'none'}")
PY
}

# The start-up alone: the device started and stopped, no request.
id=$(shm create)
__AFL_SHM_ID=$id MBSTORM_COVERAGE_PCS="$work/pcs-startup" "$work/device" --port 0 "${device_flags[@]}" >/dev/null &
sleep 1
kill $! && wait $! 2>/dev/null || true
echo "start-up alone: $(shm count "$id") edges"
shm remove "$id"

id=$(shm create)
fuzz blackbox "exec env __AFL_SHM_ID=$id AFL_MAP_SIZE=65536 MBSTORM_COVERAGE_PCS=$work/pcs-bb $work/device --port $port ${device_flags[*]}"
echo "black-box: $(shm count "$id" "$work/pcs-bb" "$work/reached-bb") edges (start-up included); $(summary blackbox)"
shm remove "$id"

fuzz coverage "exec $work/device --port $port ${device_flags[*]}" --coverage --coverage-report "$work/unreached.txt"
/usr/bin/python3 - "$work/coverage.json" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))["coverage"]
print(f"coverage: {c['edges']} edges (reached by cases), corpus {c['corpus']}, "
      f"{c['compared_constants']} compared constants; edges at 5/15/30 s: " +
      ", ".join(str(max([e for t, e in c["edges_over_time"] if t <= s] or [0])) for s in (5, 15, 30)))
PY
echo "coverage: $(summary coverage)"
echo "coverage-report: $(head -1 "$work/unreached.txt")"

# modbus.c's functions: reached by each run (the coverage run's: every function not listed
# as never reached).
nm --defined-only "$work/modbus.o" | awk '$2 ~ /^[Tt]$/ && $3 !~ /^sancov\./ {print $3}' | sort >"$work/all-modbus"
grep -E ' modbus\.c$' "$work/reached-bb" | awk '{print $1}' | grep -v '^sancov\.' | sort >"$work/bb-modbus"
grep -E ':[0-9]+$' "$work/unreached.txt" | grep '/modbus\.c:' | awk '{print $1}' | sort >"$work/never-cov"
comm -23 "$work/all-modbus" "$work/never-cov" | grep -v '^sancov\.' >"$work/cov-modbus"
echo "modbus.c functions reached: black-box $(wc -l <"$work/bb-modbus"), coverage $(wc -l <"$work/cov-modbus") of $(wc -l <"$work/all-modbus")"
echo "  coverage only: $(comm -13 "$work/bb-modbus" "$work/cov-modbus" | tr '\n' ' ')"
echo "  black-box only: $(comm -23 "$work/bb-modbus" "$work/cov-modbus" | tr '\n' ' ')"
echo "  neither: $(comm -23 "$work/all-modbus" <(sort -u "$work/bb-modbus" "$work/cov-modbus") | tr '\n' ' ')"
