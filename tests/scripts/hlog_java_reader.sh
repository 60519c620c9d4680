#!/usr/bin/env bash
# `run --hlog` writes an interval log HdrHistogram's own reader decodes to the run's counts:
# HistogramLogReader (Debian's libhdrhistogram-java, driven by java/HlogDump.java) reads every
# interval of a two-operation scenario, and each one matches the run's JSON (latency count,
# max, p50, p99 per interval; count per operation), and the sum of the untagged intervals has
# the run's .hgrm distribution line for line. A run killed with SIGKILL leaves a log of the
# intervals it completed, which the reader decodes too. setup.sh installs the JDK and the
# library.
#   bash hlog_java_reader.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
scripts=$(cd "$2" && pwd)
root=$(cd "$scripts/../.." && pwd)
jar=/usr/share/java/hdrhistogram.jar
for need in javac java "$jar"; do
  command -v "$need" >/dev/null || [ -e "$need" ] || { echo "FAIL $need is missing: run scripts/setup.sh"; exit 1; }
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"

javac -d "$work" -cp "$jar" "$scripts/java/HlogDump.java" || { echo "FAIL HlogDump.java did not compile"; exit 1; }
"$mbstorm" run "$root/scenarios/ci-gate.yaml" -d 3500ms --warmup 500ms -q \
  --hlog run.hlog --json run.json --hdr run.hgrm >run.out 2>run.err
code=$?
if [ $code -gt 1 ] || [ ! -s run.hlog ]; then
  echo "FAIL mbstorm run exited $code"; sed 's/^/  /' run.err | tail -5; exit 1
fi
timeout 120 java -cp "$jar:$work" HlogDump run.hlog java.hgrm >java.txt 2>java.err ||
  { echo "FAIL HistogramLogReader could not read the log"; sed 's/^/  /' java.err | head; exit 1; }

# Killed mid-run: every completed interval is in the file already (written and flushed as it
# ended), and the reader decodes each of them.
"$mbstorm" run -d 20s -c 1 --depth 1 -q --hlog killed.hlog >/dev/null 2>&1 &
killed=$!
sleep 3.5
kill -KILL $killed
wait $killed 2>/dev/null
timeout 120 java -cp "$jar:$work" HlogDump killed.hlog killed.hgrm >killed.txt 2>killed.err
untagged=$(grep -c '^interval - ' killed.txt)
if [ "$untagged" -ge 2 ] && ! grep -q '^interval - [0-9.]* 0 ' killed.txt; then
  echo "ok   a run killed after 3.5 s left $untagged intervals in its log, each decoded with its latencies"
else
  echo "FAIL a killed run's log: $untagged intervals decoded"; sed 's/^/  /' killed.txt killed.err | head; exit 1
fi

/usr/bin/python3 - run.json java.txt run.hgrm java.hgrm <<'PY'
import json, sys
run = json.load(open(sys.argv[1]))
lines = [l.split() for l in open(sys.argv[2])]
fail = []
def lowest(v):
    # HdrHistogram's lowest equivalent value: 3 significant digits, 2048 sub-buckets.
    shift = max(0, v.bit_length() - 11)
    return (v >> shift) << shift

intervals = {}
totals = {}
for l in lines:
    if l[0] == "interval":
        tag, start, count, mx, p50, p99 = l[1], float(l[2]), *map(int, l[3:])
        intervals.setdefault(tag, {})[round(start / run["timeline"]["interval_s"])] = (count, mx, p50, p99)
    elif l[0] == "total":
        totals[l[1]] = tuple(map(int, l[2:]))

names = [op["name"] for op in run["operations"]]
if set(intervals) != {"-", *names}:
    fail.append(f"tags in the log {sorted(intervals)}, operations {names}")
json_iv = run["timeline"]["intervals"]
if not json_iv:
    fail.append("the JSON has no intervals")
log = intervals.get("-", {})
# The JSON folds a last sliver of an interval into the one before and drops empty intervals
# past the end: group the log's intervals the same way.
for i, iv in enumerate(json_iv):
    first = iv["index"]
    last = json_iv[i + 1]["index"] - 1 if i + 1 < len(json_iv) else max(log, default=first)
    group = [log.get(k, (0, 0, 0, 0)) for k in range(first, last + 1)]
    count = sum(g[0] for g in group)
    if count != iv["latency_count"]:
        fail.append(f"interval {first}: the log holds {count} latencies, the JSON {iv['latency_count']}")
    if iv["latency_count"] == 0:
        continue
    head = group[0]
    for name, j, l in (("p50", iv["p50_ns"], head[2]), ("p99", iv["p99_ns"], head[3])):
        if lowest(j) != l:
            fail.append(f"interval {first}: {name} {j} ns in the JSON, bucket {l} in the log")
    if len(group) == 1 and lowest(iv["max_ns"]) != head[1]:
        fail.append(f"interval {first}: max {iv['max_ns']} ns in the JSON, bucket {head[1]} in the log")
whole = run["latency"]
if totals.get("-", (None,))[0] != whole["count"]:
    fail.append(f"whole run: {totals.get('-')} in the log, count {whole['count']} in the JSON")
elif lowest(whole["percentiles_ns"]["99"]) != totals["-"][3] or lowest(whole["max_ns"]) != totals["-"][1]:
    fail.append(f"whole run: p99/max {whole['percentiles_ns']['99']}/{whole['max_ns']} vs log {totals['-']}")
for op in run["operations"]:
    got = totals.get(op["name"], (0,))[0]
    if got != op["latency"]["count"]:
        fail.append(f"operation {op['name']}: {got} latencies in the log, {op['latency']['count']} in the JSON")
    if intervals.get(op["name"]) and lowest(op["latency"]["percentiles_ns"]["50"]) != totals[op["name"]][2]:
        fail.append(f"operation {op['name']}: p50 differs")

# .hgrm: ours from the run, HdrHistogram's from the sum of the log's untagged intervals.
def rows(path):
    out, footer = [], []
    for l in open(path):
        f = l.split()
        if l.startswith("#"):
            footer.append(" ".join(f))
        elif len(f) >= 3 and f[0][0].isdigit():
            out.append((float(f[0]), float(f[1]), int(f[2])))
    return out, footer
ours, our_footer = rows(sys.argv[3])
theirs, their_footer = rows(sys.argv[4])
if len(ours) != len(theirs):
    fail.append(f".hgrm: {len(ours)} rows from mbstorm, {len(theirs)} from HdrHistogram")
for a, b in zip(ours, theirs):
    # Same percentile steps and cumulative counts; values equal but for the top bucket, where
    # mbstorm shows the exact max rather than the bucket's upper edge.
    if abs(a[1] - b[1]) > 1e-6 or a[2] != b[2] or not (a[0] <= b[0] + 0.0005 and a[0] >= b[0] * 0.999 - 0.0005):
        fail.append(f".hgrm row differs: mbstorm {a}, HdrHistogram {b}")
        break
if our_footer[-1] != their_footer[-1]:
    fail.append(f"bucket layout differs: {our_footer[-1]} vs {their_footer[-1]}")
if fail:
    print("FAIL " + "\nFAIL ".join(fail))
    sys.exit(1)
n = sum(1 for l in lines if l[0] == "interval")
print(f"ok   HistogramLogReader decoded {n} interval lines ({len(names)} operations + all); "
      f"counts, max, p50, p99 and the .hgrm rows match the run's JSON and .hgrm")
PY
