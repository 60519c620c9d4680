#!/usr/bin/env bash
# One place per fact: outside codec/ (and the slave that serves the codes) no source names a
# function code or frames/cuts MBAP by hand beyond the budgets in one_place_allow.txt (each
# with its reason). First proves the check can fail: a planted `case 0x17:` and a planted
# `6u + h.length` must both be reported.
# Likewise the fuzzer's root-cause rule texts live in src/netfuzz/rules.hpp (issue #26): no
# other .cpp under src/netfuzz spells one of its hyphenated constants as a literal (a planted
# one must be reported first).
set -euo pipefail
scripts=$(cd "$2" && pwd)
root=$(cd "$scripts/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

mkdir -p "$work/src/load" "$work/src/codec" "$work/tests/scripts"
cp "$scripts/one_place_allow.txt" "$work/tests/scripts/"
# The codes are the codec's table: a code added there (0x7E here) is looked for too.
sed 's|^    EncapsulatedInterface = 0x2B,|&\n    PlantedCode = 0x7E,|' "$root/src/codec/function_code.hpp" >"$work/src/codec/function_code.hpp"
sed 's|^constexpr std::array<FunctionInfo, [0-9]*> kFunctions{{|&\n    {PlantedCode, "planted_code"},|' "$root/src/codec/function_code.cpp" >"$work/src/codec/function_code.cpp"
grep -q 'PlantedCode = 0x7E' "$work/src/codec/function_code.hpp" && grep -q '"planted_code"' "$work/src/codec/function_code.cpp" ||
  { echo "FAIL could not plant a code in a copy of the codec's table" >&2; exit 1; }
printf 'int f(int fc) {\n    switch (fc) {\n        case 0x17:\n            return 1;\n    }\n    return 0;\n}\n' >"$work/src/load/planted.cpp"
printf 'unsigned cut(const H& h) { return 6u + h.length; }\n' >>"$work/src/load/planted.cpp"
printf 'int n(int fc) { return fc == 0x7E; }\n' >>"$work/src/load/planted.cpp"
printf 'std::vector<std::uint8_t> pre{0x06};\n' >>"$work/src/load/planted.cpp"
printf 'bool d(Pdu pdu) { return pdu[0] == 0x08; }\n' >>"$work/src/load/planted.cpp"
printf 'bool busy(const std::uint8_t* p) { return p[8] == 0x06; }\n' >>"$work/src/load/planted.cpp"
printf 'int g(int fc) { return fc == 0x17; }  // codec/ owns the codes\n' >"$work/src/codec/owner.cpp"
printf '// one-place: a justified site\nint j(int fc) { return fc == 0x10; }\n' >"$work/src/load/justified.cpp"
if /usr/bin/python3 "$scripts/lib/one_place.py" "$work" >"$work/self.log" 2>&1; then
  echo "FAIL the check passed planted sites:" >&2; cat "$work/self.log" >&2; exit 1
fi
for expected in "case 0x17:" "6u + h.length" "fc == 0x7E" "pre{0x06}" "pdu[0] == 0x08" "p[8] == 0x06"; do
  grep -qF "$expected" "$work/self.log" || { echo "FAIL the check did not report '$expected'" >&2; cat "$work/self.log" >&2; exit 1; }
done
if grep -q "owner.cpp\|justified.cpp" "$work/self.log"; then
  echo "FAIL the check reported a codec/ site or a justified one:" >&2; cat "$work/self.log" >&2; exit 1
fi

/usr/bin/python3 "$scripts/lib/one_place.py" "$root"

# Prints each `"text"` literal in src/netfuzz/*.cpp (rules.cpp aside, where the parameterised
# rules are put together) that equals a hyphenated rule constant of rules.hpp; fails if any.
# Single words ("capacity", "fc") are left out: they are too common to tell apart.
rule_literals() {
  local dir=$1/src/netfuzz texts found=0 text
  # Constants may be wrapped onto the next line by clang-format: join the lines first.
  texts=$(tr '\n' ' ' <"$dir/rules.hpp" |
    grep -oE 'constexpr const char\* k[A-Za-z0-9]+ = +"[^"]*-[^"]*"' | sed 's/.*= *"\(.*\)"/\1/')
  if [ "$(printf '%s\n' "$texts" | grep -c .)" -lt 20 ] || ! grep -qx 'target-down' <<<"$texts"; then
    echo "FAIL could not read the rule constants of $dir/rules.hpp" >&2
    return 1
  fi
  while IFS= read -r text; do
    if grep -nF "\"$text\"" --include='*.cpp' --exclude='rules.cpp' -r "$dir"; then found=1; fi
  done <<<"$texts"
  return $found
}

mkdir -p "$work/src/netfuzz"
cp "$root/src/netfuzz/rules.hpp" "$work/src/netfuzz/"
printf 'const char* r() { return "drops-requests-after-exception"; }\n' >"$work/src/netfuzz/planted.cpp"
printf 'const char* r() { return "target-down"; }  // the one place\n' >"$work/src/netfuzz/rules.cpp"
if rule_literals "$work" >"$work/rules.log" 2>&1; then
  echo "FAIL the rule check passed a planted literal:" >&2; cat "$work/rules.log" >&2; exit 1
fi
if ! grep -q 'planted.cpp:1:' "$work/rules.log" || grep -q 'rules.cpp' "$work/rules.log"; then
  echo "FAIL the rule check did not report just the planted literal:" >&2; cat "$work/rules.log" >&2; exit 1
fi
if ! rule_literals "$root" >"$work/rules.log" 2>&1; then
  echo "FAIL rule texts spelled outside src/netfuzz/rules.hpp (name the constant instead):" >&2
  cat "$work/rules.log" >&2
  exit 1
fi
