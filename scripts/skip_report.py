#!/usr/bin/python3
"""Reads a CTest JUnit file (ctest --output-junit) and says which tests skipped, whole or in
part, and why. A test skips whole when CTest says so (GTEST_SKIP, or a script's exit 77); a
script test skips in part when it passes but printed a line saying it skipped a peer.

Under CI=true a skip fails the run unless its reason matches a line of
scripts/allowed-skips.txt: what a machine may lack that no package provides (a kernel feature,
IPv6 on loopback, a capability). A skip for a missing program or module is a bug there:
scripts/setup.sh installs every one.

Usage: skip_report.py JUNIT_FILE STAGE"""
import os
import re
import sys
import xml.etree.ElementTree as ET

here = os.path.dirname(os.path.abspath(__file__))
allowed = [re.compile(line.split("#")[0].strip())
           for line in open(os.path.join(here, "allowed-skips.txt"))
           if line.split("#")[0].strip()]
# How the script tests say they skipped something: "skip: ..." or "...: skipped [that peer]"
# at the end of the line (not a count such as "cases skipped as known crash/hang: 0").
partial = re.compile(r"^skip:|\bskipped( that peer)?\s*$", re.IGNORECASE)
gtest_reason = re.compile(r"^.*?:\d+: Skipped\s*$")


def reason_of(out, whole):
    lines = [l.strip() for l in (out or "").splitlines() if l.strip()]
    if whole:
        # GTEST_SKIP: the message follows the "file:line: Skipped" line.
        for i, l in enumerate(lines):
            if gtest_reason.match(l) and i + 1 < len(lines):
                return lines[i + 1]
    for l in lines:
        if partial.search(l):
            return l
    return lines[-1] if lines else "(no reason printed)"


skips = []
for case in ET.parse(sys.argv[1]).getroot().iter("testcase"):
    name, status = case.get("name"), case.get("status")
    out = case.findtext("system-out")
    if status in ("skipped", "notrun", "disabled"):
        skips.append((name, reason_of(out, True), "skipped"))
    elif status == "run" and name.startswith("script.") and any(
            partial.search(l) for l in (out or "").splitlines()):
        skips.append((name, reason_of(out, False), "skipped in part"))

stage = sys.argv[2]
if not skips:
    print(f"{stage}: no test skipped")
    sys.exit(0)
bad = [s for s in skips if not any(a.search(s[1]) for a in allowed)]
print(f"{stage}: {len(skips)} test(s) skipped, whole or in part:")
for name, reason, how in skips:
    mark = "  NOT ALLOWED" if (name, reason, how) in bad else ""
    print(f"  {name} ({how}): {reason}{mark}")
if bad and os.environ.get("CI") == "true":
    print(f"{stage}: under CI=true a test may skip only for what scripts/allowed-skips.txt lists")
    sys.exit(1)
sys.exit(0)
