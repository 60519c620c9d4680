#!/usr/bin/env bash
# Peak memory of `run` with and without --hlog on scenarios of many operations (issue #31):
# each operation keeps latency histograms of its own. Prints one line per scenario.
#
#   bench/run_hlog_memory.sh [BUILD_DIR] [SECONDS]
set -euo pipefail
build=${1:-build/release}
seconds=${2:-3}
bin=$(realpath "$build/mbstorm")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

scenario() {  # OPS CONNECTIONS > yaml
    printf 'name: many-ops\nconnections: %s\ndepth: 4\noperations:\n' "$2"
    for ((i = 0; i < $1; i++)); do
        printf '  - name: op%d\n    function: read_holding_registers\n' "$i"
        printf '    address: %d\n    quantity: 1\n' $((i % 1000))
    done
}

peak_mb() {  # ARGS...: Max RSS of the run in MB
    /usr/bin/time -v "$bin" "$@" >"$work/out" 2>"$work/err" || {
        cat "$work/out" "$work/err" >&2
        exit 1
    }
    awk '/Maximum resident set size/ {printf "%.0f", $6 / 1024}' "$work/err"
}

for shape in "1000 4 1" "100 8 4"; do
    read -r ops connections threads <<<"$shape"
    scenario "$ops" "$connections" >"$work/s.yaml"
    args=(run "$work/s.yaml" -d "${seconds}s" --threads "$threads" --slave-threads 1)
    without=$(peak_mb "${args[@]}")
    with=$(peak_mb "${args[@]}" --hlog "$work/run.hlog")
    lines=$(grep -c -v '^[#"]' "$work/run.hlog")
    echo "$ops operations, $threads thread(s): without --hlog ${without} MB, with --hlog ${with} MB ($lines log lines)"
done
