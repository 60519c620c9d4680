#!/usr/bin/env bash
# One place per fact: outside codec/ (and the slave that serves the codes) no source names a
# function code or frames/cuts MBAP by hand beyond the budgets in one_place_allow.txt (each
# with its reason). First proves the check can fail: a planted `case 0x17:` and a planted
# `6u + h.length` must both be reported.
set -euo pipefail
scripts=$(cd "$2" && pwd)
root=$(cd "$scripts/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

mkdir -p "$work/src/load" "$work/src/codec" "$work/tests/scripts"
cp "$scripts/one_place_allow.txt" "$work/tests/scripts/"
printf 'int f(int fc) {\n    switch (fc) {\n        case 0x17:\n            return 1;\n    }\n    return 0;\n}\n' >"$work/src/load/planted.cpp"
printf 'unsigned cut(const H& h) { return 6u + h.length; }\n' >>"$work/src/load/planted.cpp"
printf 'int g(int fc) { return fc == 0x17; }  // codec/ owns the codes\n' >"$work/src/codec/owner.cpp"
printf '// one-place: a justified site\nint j(int fc) { return fc == 0x10; }\n' >"$work/src/load/justified.cpp"
if /usr/bin/python3 "$scripts/lib/one_place.py" "$work" >"$work/self.log" 2>&1; then
  echo "FAIL the check passed planted sites:" >&2; cat "$work/self.log" >&2; exit 1
fi
for expected in "case 0x17:" "6u + h.length"; do
  grep -qF "$expected" "$work/self.log" || { echo "FAIL the check did not report '$expected'" >&2; cat "$work/self.log" >&2; exit 1; }
done
if grep -q "owner.cpp\|justified.cpp" "$work/self.log"; then
  echo "FAIL the check reported a codec/ site or a justified one:" >&2; cat "$work/self.log" >&2; exit 1
fi

/usr/bin/python3 "$scripts/lib/one_place.py" "$root"
