#!/usr/bin/env bash
# What `mbstorm merge` takes to merge two shards of a long soak, and what it does with inputs
# edited to make it allocate without bound (issue #31 item 2). Max RSS from /usr/bin/time -v.
#
#   bench/run_merge_memory.sh BUILD_DIR [HOURS] [OTHER_MBSTORM]
#
# Two 5-s shards run side by side against `mbstorm serve` on loopback; make_soak_shards.py
# stretches their real interval logs and JSONs to HOURS (default 8) and to 10 minutes; each is
# merged. OTHER_MBSTORM (an older build) is measured beside, under a 6 GB address-space limit
# so that it cannot take the machine: it dies of bad_alloc (exit 134) where it would need more.
set -euo pipefail
build=${1:?usage: run_merge_memory.sh BUILD_DIR [HOURS] [OTHER_MBSTORM]}
hours=${2:-8}
other=${3:-}
mbstorm=$(realpath "$build/mbstorm")
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'kill "$serve_pid" 2>/dev/null || true; rm -rf "$work"' EXIT
cd "$work"

port=$((20000 + RANDOM % 20000))
"$mbstorm" serve --listen "127.0.0.1:$port" --duration 30s >serve.log 2>&1 &
serve_pid=$!
sleep 1
for i in 0 1; do
    "$mbstorm" run --target "127.0.0.1:$port" -c 4 -d 5s --shard "$i/2" --test-id soak \
        --json "s$i.json" --hlog "s$i.hlog" >"run$i.log" 2>&1 &
done
wait %2 %3
python3 "$here/make_soak_shards.py" "$hours" long s0.json s0.hlog s1.json s1.hlog
python3 "$here/make_soak_shards.py" 0.1667 short s0.json s0.hlog s1.json s1.hlog

# merge BINARY DIR [LIMIT_KB]: exit code, Max RSS and wall time of merging DIR's two shards.
measure() {
    local bin=$1 dir=$2 limit=${3:-unlimited} rc=0
    (ulimit -v "$limit" && /usr/bin/time -v "$bin" merge "$dir"/s0.json "$dir"/s0.hlog \
        "$dir"/s1.json "$dir"/s1.hlog --json "$dir/merged.json") >/dev/null 2>"$dir/err" || rc=$?
    printf '  %-40s exit %3d  max RSS %8d KB  %s s  %s\n' "$(basename "$bin") $(basename "$dir")" \
        "$rc" "$(awk '/Maximum resident/ {print $6}' "$dir/err")" \
        "$(awk -F': ' '/Elapsed/ {print $2}' "$dir/err")" \
        "$(grep -m1 'mbstorm merge:' "$dir/err" | cut -c1-120)"
}

# Crafted from the 5-s shards: one number edited in the JSONs given (and the logs' first line
# where it names the shard count, so that the files still agree).
craft() {
    local name=$1 which=$2 filter=$3
    mkdir -p "$name"
    cp s0.json s0.hlog s1.json s1.hlog "$name"/
    for i in $which; do
        python3 -c "import json; d=json.load(open('s$i.json')); $filter
json.dump(d, open('$name/s$i.json', 'w'))"
    done
}
craft day_apart 1 "d['test']['measure_start_epoch_s'] += 86400"
craft ten_days_apart 1 "d['test']['measure_start_epoch_s'] += 864000"  # near the 1e6-slot cap
craft interval_1us "0 1" "d['timeline']['interval_s'] = 1e-6"
craft shards_2e9 "0 1" "d['test']['shard_count'] = 2000000000"
sed -i '1s|/2]$|/2000000000]|' shards_2e9/s0.hlog shards_2e9/s1.hlog
craft duration_1e300 1 "d['run']['measured_duration_s'] = 1e300"

for dir in short long; do
    echo "$dir: $(du -h $dir/s0.hlog | cut -f1) + $(du -h $dir/s1.hlog | cut -f1) of interval logs"
done
for bin in "$mbstorm" ${other:+"$other"}; do
    echo "$bin:"
    for dir in short long day_apart ten_days_apart interval_1us shards_2e9 duration_1e300; do
        measure "$bin" "$dir" $((6 * 1024 * 1024))
    done
done
