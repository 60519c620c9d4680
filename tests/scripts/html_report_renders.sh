#!/usr/bin/env bash
# Runs a short load test against the embedded slave, writes the HTML report, and renders it in
# headless Chromium: the page must load with no network access, contain its plots, and
# produce a non-trivial screenshot.
set -euo pipefail
mbstorm=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$mbstorm" run -d 1s -c 4 --depth 4 -q --html "$work/report.html" --json "$work/report.json" --hdr "$work/report.hgrm" >"$work/run.log"

if ! command -v chromium >/dev/null; then
  echo "chromium is not installed (scripts/setup.sh installs it)" >&2
  exit 1
fi
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking
       --disable-component-update --disable-sync --user-data-dir="$work/profile" --window-size=1280,2400)
timeout 120 chromium "${flags[@]}" --screenshot="$work/report.png" "file://$work/report.html" >/dev/null 2>&1
timeout 120 chromium "${flags[@]}" --dump-dom "file://$work/report.html" 2>/dev/null >"$work/dom.html"

size=$(stat -c %s "$work/report.png")
[ "$size" -gt 20000 ] || { echo "screenshot too small ($size bytes): page did not render" >&2; exit 1; }
svgs=$(grep -o '<svg' "$work/dom.html" | wc -l)
[ "$svgs" -ge 3 ] || { echo "rendered page has $svgs SVG plots, expected at least 3" >&2; exit 1; }
grep -q 'polyline\|<path' "$work/dom.html" || { echo "plots have no lines" >&2; exit 1; }
# Self-contained: no scripts or stylesheets fetched from anywhere.
if grep -Eo '(src|href)="https?://' "$work/report.html"; then
  echo "report fetches from the network" >&2; exit 1
fi
echo "html report rendered: $svgs plots, screenshot $size bytes"
