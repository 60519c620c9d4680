#!/usr/bin/env bash
# Server throughput table: FC03 x10 requests, depth 1/16/256 over 1/64/1000 connections,
# against mbstorm's io_uring slave (1 thread), the epoll limit_server, a libmodbus server and
# pymodbus. Server pinned to core 0, client (pipeline_client) to core 1.
#
#   bench/run_server_bench.sh [build-dir] [seconds-per-cell]
#   SERVERS="mbstorm libmodbus" CELLS="16:16 64:1" bench/run_server_bench.sh ...   (a subset)
#   REPEATS=5 ...   medians of 5 runs, the servers taking turns within each repeat
# Prints markdown tables of transactions/s and of transactions per server CPU-second (the
# client is single-threaded, so on a small machine it often saturates before a fast server
# does; the server's own CPU time shows its efficiency), and the ratios the project targets.
set -u
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-$here/../build/release}
secs=${2:-2}
repeats=${REPEATS:-1}
client="$build/bench/pipeline_client"
limit="$build/bench/limit_server"
libmodbus="$build/bench/libmodbus_server"
mbstorm="$build/tests/mbstorm_test_server"
for f in "$client" "$limit" "$mbstorm"; do
  [ -x "$f" ] || { echo "missing $f (build the bench/ and tests/tools targets)" >&2; exit 1; }
done
ulimit -n 20000 2>/dev/null || true

source "$here/lib/servers.bash"
trap stop_server EXIT

cpu_ticks() { awk '{print $14 + $15}' "/proc/$1/stat" 2>/dev/null || echo 0; }
hz=$(getconf CLK_TCK)

declare -A tps eff
tmp_result=$(mktemp)
servers=${SERVERS:-"mbstorm limit libmodbus pymodbus"}
[ -x "$libmodbus" ] || servers=${servers/libmodbus/}
cells=${CELLS:-"1:1 1:16 1:256 16:16 64:1 64:16 64:256 1000:1 1000:16 1000:256"}
# One measurement: prints "tps transactions-per-server-CPU-second" (or "n/a n/a").
measure() {
  local s=$1 c=$2 d=$3
  if ! start_server "$s"; then stop_server; echo "n/a n/a"; return; fi
  # The server's CPU time over the measured window (after the client's warm-up).
  timeout $((secs + 30)) taskset -c 1 "$client" --port "$port" --connections "$c" \
    --depth "$d" --seconds "$secs" --warmup 0.5 >"$tmp_result" 2>/dev/null &
  local cpid=$!
  sleep 0.6
  local t0 w0 t1 w1 line v cpu
  t0=$(cpu_ticks "$server_pid"); w0=$(date +%s.%N)
  wait "$cpid"
  t1=$(cpu_ticks "$server_pid"); w1=$(date +%s.%N)
  line=$(grep '^RESULT' "$tmp_result")
  v=$(sed -n 's/.*tps=\([0-9]*\).*/\1/p' <<<"$line")
  cpu=$(awk -v a="$t0" -v b="$t1" -v hz="$hz" -v w0="$w0" -v w1="$w1" \
        'BEGIN{ f=(b-a)/hz/(w1-w0); if (f < 0.01) f=0.01; printf "%.2f", f }')
  echo "# $s conns=$c depth=$d: ${line:-failed} server_cpu=$cpu" >&2
  stop_server
  echo "${v:-n/a} $(awk -v t="${v:-0}" -v f="$cpu" 'BEGIN{ if (t > 0) printf "%.0f", t/f; else print "n/a" }')"
}
median() { tr ' ' '\n' | grep -v '^$' | sort -n | awk '{a[NR]=$1} END {if (NR == 0) print "n/a"; else print a[int((NR+1)/2)]}'; }

# This VM's throughput drifts by +-20 % from minute to minute: the servers take turns within
# each repeat (so all see the same conditions) and each figure is the median of the repeats.
for cell in $cells; do
  c=${cell%%:*}; d=${cell##*:}
  declare -A runs_t=() runs_e=()
  for _ in $(seq "$repeats"); do
    for s in $servers; do
      read -r t e < <(measure "$s" "$c" "$d")
      [ "$t" != "n/a" ] && runs_t[$s]+="$t " && runs_e[$s]+="$e "
    done
  done
  for s in $servers; do
    tps[$s,$c,$d]=$(median <<<"${runs_t[$s]:-}")
    eff[$s,$c,$d]=$(median <<<"${runs_e[$s]:-}")
  done
done

printf '\n| connections x depth |'
for s in $servers; do printf ' %s |' "$s"; done
printf '\n|---|'; for s in $servers; do printf -- '---:|'; done; printf '\n'
for cell in $cells; do
  c=${cell%%:*}; d=${cell##*:}
  printf '| %s x %s |' "$c" "$d"
  for s in $servers; do printf ' %s |' "${tps[$s,$c,$d]}"; done
  printf '\n'
done
printf '\nTransactions per server CPU-second:\n\n| connections x depth |'
for s in $servers; do printf ' %s |' "$s"; done
printf '\n|---|'; for s in $servers; do printf -- '---:|'; done; printf '\n'
for cell in $cells; do
  c=${cell%%:*}; d=${cell##*:}
  printf '| %s x %s |' "$c" "$d"
  for s in $servers; do printf ' %s |' "${eff[$s,$c,$d]}"; done
  printf '\n'
done
ratio() { awk -v a="$1" -v b="$2" 'BEGIN{ if (b+0 > 0 && a+0 > 0) printf "%.2f", a/b; else print "n/a" }'; }
echo
echo "mbstorm / limit_server at 16x16: $(ratio "${tps[mbstorm,16,16]:-0}" "${tps[limit,16,16]:-0}") (target >= 0.8)"
echo "mbstorm / libmodbus at 16x16:   $(ratio "${tps[mbstorm,16,16]:-0}" "${tps[libmodbus,16,16]:-0}") (target >= 10)"
echo "mbstorm / libmodbus at 64x1:    $(ratio "${tps[mbstorm,64,1]:-0}" "${tps[libmodbus,64,1]:-0}") (target >= 2)"
echo "per server CPU-second: vs limit 16x16 $(ratio "${eff[mbstorm,16,16]:-0}" "${eff[limit,16,16]:-0}"), vs libmodbus 16x16 $(ratio "${eff[mbstorm,16,16]:-0}" "${eff[libmodbus,16,16]:-0}"), vs libmodbus 64x1 $(ratio "${eff[mbstorm,64,1]:-0}" "${eff[libmodbus,64,1]:-0}")"
rm -f "$tmp_result"
