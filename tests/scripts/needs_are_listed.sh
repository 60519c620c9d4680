#!/usr/bin/env bash
# Every program and python module that the test and benchmark scripts use is listed in
# scripts/test-needs.txt, which scripts/setup.sh installs and checks (lib/needs.py says how
# uses are found). First proves the check can fail: a script running an unlisted program and
# one importing an unlisted module must both be reported.
set -euo pipefail
scripts=$(cd "$2" && pwd)
root=$(cd "$scripts/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

mkdir -p "$work/scripts" "$work/tests/scripts"
cp "$root/scripts/test-needs.txt" "$work/scripts/"
printf '#!/usr/bin/env bash\nout=$(mktemp)\nif ! x=$(jq -r .a "$out" | sort); then exit 1; fi\n' >"$work/tests/scripts/uses_jq.sh"
printf 'import json\nfrom bottle import route\n' >"$work/tests/scripts/uses_bottle.py"
if /usr/bin/python3 "$scripts/lib/needs.py" "$work" >"$work/self.log"; then
  echo "FAIL the check passed scripts that use jq and bottle:" >&2; cat "$work/self.log" >&2; exit 1
fi
for expected in "program 'jq'" "module 'bottle'"; do
  grep -q "$expected" "$work/self.log" || { echo "FAIL the check did not report $expected" >&2; cat "$work/self.log" >&2; exit 1; }
done
if grep -q "'mktemp'\|'sort'\|'json'" "$work/self.log"; then
  echo "FAIL the check reported a listed program or a standard module:" >&2; cat "$work/self.log" >&2; exit 1
fi

/usr/bin/python3 "$scripts/lib/needs.py" "$root"
