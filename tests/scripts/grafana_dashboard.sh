#!/usr/bin/env bash
# deploy/grafana/mbstorm.json parses as a Grafana dashboard, and every metric name its queries
# use is one that `mbstorm run` or `mbstorm serve` exports (read from their /metrics).
#   bash grafana_dashboard.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
scripts=$(cd "$2" && pwd)
dashboard="$scripts/../../deploy/grafana/mbstorm.json"
work=$(mktemp -d)
pid=""
trap '[ -n "$pid" ] && kill "$pid" 2>/dev/null; wait 2>/dev/null; rm -rf "$work"' EXIT
# scrape OUT ARGS...: starts mbstorm ARGS --metrics-listen 127.0.0.1:0 and saves one scrape.
scrape() {
  local out=$1; shift
  "$mbstorm" "$@" --metrics-listen 127.0.0.1:0 >"$work/out" 2>"$work/err" &
  pid=$!
  local url=""
  # Up to 30 s to start: the suites run two tests per core beside it (it once missed 10 s).
  for _ in $(seq 300); do
    url=$(sed -n 's/.*metrics on \(http:[^ ]*\).*/\1/p' "$work/err"); [ -n "$url" ] && break
    sleep 0.1
  done
  [ -n "$url" ] && curl -s --retry 3 --retry-connrefused -o "$out" "$url"
  kill "$pid" 2>/dev/null; wait "$pid" 2>/dev/null; pid=""
  [ -s "$out" ]
}
scrape "$work/run.prom" run -d 20s -c 1 -q || { echo "FAIL no scrape of run"; exit 1; }
scrape "$work/serve.prom" serve --listen 127.0.0.1:0 --threads 1 -d 20s ||
  { echo "FAIL no scrape of serve"; sed 's/^/  /' "$work/err"; exit 1; }
/usr/bin/python3 - "$dashboard" "$work/run.prom" "$work/serve.prom" <<'PY'
import json, re, sys
dashboard = json.load(open(sys.argv[1]))
exported = set()
for path in sys.argv[2:]:
    for line in open(path):
        m = re.match(r"# TYPE (\S+) (\S+)", line)
        if m:
            exported.add(m.group(1))
            if m.group(2) == "histogram":
                exported.update(m.group(1) + s for s in ("_bucket", "_sum", "_count"))
fail = False
def check(ok, what):
    global fail
    print(("ok   " if ok else "FAIL ") + what)
    fail = fail or not ok
check(isinstance(dashboard.get("panels"), list) and dashboard["panels"], "the dashboard has panels")
check(dashboard.get("title") and dashboard.get("uid"), "it has a title and a uid")
exprs = [t["expr"] for p in dashboard["panels"] for t in p.get("targets", [])]
exprs += [v["query"]["query"] for v in dashboard.get("templating", {}).get("list", [])]
used = set()
for e in exprs:
    used.update(re.findall(r"\bmbstorm_[a-z_]+", e))
check(len(used) >= 10, f"its queries use {len(used)} mbstorm metrics")
for name in sorted(used):
    check(name in exported, f"{name} is exported")
titles = " ".join(p["title"].lower() for p in dashboard["panels"])
for want in ("throughput", "error", "heatmap", "connections"):
    check(want in titles, f"a panel about {want}")
check(any(p["type"] == "heatmap" and "_bucket" in p["targets"][0]["expr"] for p in dashboard["panels"]),
      "the heatmap is built from the histogram's buckets")
sys.exit(1 if fail else 0)
PY
