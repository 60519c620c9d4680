#!/usr/bin/env python3
"""Counts function-code knowledge and hand-made MBAP framing outside the codec.

Usage: one_place.py ROOT [--list]

Two facts have one owner each (docs/architecture.md): what a function code is (codec/, and
the slave that serves it) and how an MBAP frame is laid out (codec/). This finds places
elsewhere under src/ that still know them:

  function-code sites: a line naming a public function code as a literal (case 0x17:,
    fc == 0x16, function == 5, pdu[0] == 0x08, a PDU started as {0x06} or pdu5(0x17, ..,
    a 0x.. literal on a line about a function code, or a label like
    "0x05 write_single_coil" in text);
  MBAP sites: a line framing or cutting MBAP by hand (the length at byte 4, 6 + length,
    protocol id 0 at byte 2, function | 0x80, the function or exception code at byte 7 or 8).

The public codes are the codec's: the FunctionCode enumerators of src/codec/function_code.hpp
and their names in the table of src/codec/function_code.cpp, so a new code is looked for
without a change here.

A site is allowed when its line or the line above carries a comment "one-place: WHY". The
rest must fit the budget that tests/scripts/one_place_allow.txt gives its file (one line:
KIND PATH COUNT  # why). Exit 1 when a file has more sites than its budget, naming them.
"""
import pathlib
import re
import sys


def public_codes(root):
    """The codec's table: {code: name} for each FunctionCode enumerator of
    src/codec/function_code.hpp, named by its row in src/codec/function_code.cpp."""
    header = (root / "src/codec/function_code.hpp").read_text(encoding="utf-8")
    body = re.search(r"enum class FunctionCode\b[^{]*\{(.*?)\};", header, re.S)
    if body is None:
        sys.exit("one_place.py: no 'enum class FunctionCode' in src/codec/function_code.hpp")
    codes = {m.group(1): int(m.group(2), 0)
             for m in re.finditer(r"(\w+)\s*=\s*(0x[0-9A-Fa-f]+|\d+)", body.group(1))}
    table = (root / "src/codec/function_code.cpp").read_text(encoding="utf-8")
    names = dict(re.findall(r"\{\s*(\w+),\s*\"(\w+)\"", table))
    missing = sorted(set(codes) - set(names))
    if not codes or missing:
        sys.exit(f"one_place.py: could not read the codec's table (no row for {missing})")
    return {code: names[enumerator] for enumerator, code in codes.items()}


OWNERS_FC = ("src/codec/", "src/slave/")
OWNERS_MBAP = ("src/codec/",)


def patterns(public):
    hexes = "|".join(f"0x{c:02X}" for c in public) + "|" + "|".join(f"0x{c:02x}" for c in public)
    decimals = "|".join(str(c) for c in public)
    fc = [
        re.compile(rf"\bcase\s+({hexes})\s*:"),
        re.compile(rf"\b(fc|function|function_code)\w*(\[\w+\])?\s*(==|!=|<=|>=)\s*({hexes}|{decimals})\b"),
        re.compile(rf"({hexes})\b[^;]*\b(fc|function)\b|\b(fc|function)\b[^;]*\b({hexes})\b"),
        re.compile(r"0x[0-9A-Fa-f]{2} (" + "|".join(public.values()) + r")\b"),
        # A PDU built from its function code: pdu5(0x17, .., std::vector<std::uint8_t> w{0x06}.
        re.compile(rf"[({{]\s*({hexes})\s*[,}})]"),
        # A PDU's first byte compared with a code: pdu[0] == 0x08, pdu[0] <= 0x04.
        re.compile(rf"\w*pdu\w*\[0\]\s*(==|!=|<=|>=|<|>)\s*({hexes}|{decimals})\b"),
    ]
    mbap = [
        re.compile(r"\b6u?\s*\+\s*[\w.>-]*length\b|\blength\s*\+\s*6u?\b"),
        re.compile(r"load_be16\(\s*[\w.]+\s*\+\s*4\s*\)"),
        re.compile(r"store_be16\(\s*[\w.]+\s*\+\s*2\s*,\s*0\s*\)"),
        re.compile(r"\|\s*0x80\b"),
        # An ADU's function code or exception code read at its MBAP offset: p[7] & 0x80, p[8] == 6.
        re.compile(r"\b\w+\[\s*[78]\s*\]\s*(&|==|!=)\s*[^'\s]"),
    ]
    return fc, mbap


MARK = "one-place:"


def strip_comment(line):
    # Drops a // comment that is not inside a string literal (good enough for this code).
    quote = False
    for i, ch in enumerate(line):
        if ch == '"' and (i == 0 or line[i - 1] != "\\"):
            quote = not quote
        if not quote and line.startswith("//", i):
            return line[:i]
    return line


def sites(root):
    fc_patterns, mbap_patterns = patterns(public_codes(root))
    found = {"fc": {}, "mbap": {}}
    for path in sorted((root / "src").rglob("*")):
        if path.suffix not in (".cpp", ".hpp"):
            continue
        rel = path.relative_to(root).as_posix()
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
        for n, raw in enumerate(lines):
            if MARK in raw or (n > 0 and MARK in lines[n - 1]):
                continue
            code = strip_comment(raw)
            for kind, owners, kind_patterns in (("fc", OWNERS_FC, fc_patterns),
                                                ("mbap", OWNERS_MBAP, mbap_patterns)):
                if rel.startswith(owners):
                    continue
                if any(p.search(code) for p in kind_patterns):
                    found[kind].setdefault(rel, []).append((n + 1, raw.strip()))
    return found


def budgets(root):
    allow = {}
    text = (root / "tests/scripts/one_place_allow.txt").read_text(encoding="utf-8")
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        kind, rel, count = line.split()
        allow[(kind, rel)] = int(count)
    return allow


def main():
    root = pathlib.Path(sys.argv[1]).resolve()
    listing = "--list" in sys.argv[2:]
    found = sites(root)
    allow = budgets(root)
    failed = False
    for kind, title in (("fc", "function-code literals"), ("mbap", "hand-made MBAP")):
        files = found[kind]
        total = sum(len(v) for v in files.values())
        print(f"{title}: {total} sites in {len(files)} files outside "
              f"{', '.join(OWNERS_FC if kind == 'fc' else OWNERS_MBAP)}")
        for rel, where in files.items():
            budget = allow.get((kind, rel), 0)
            if listing or len(where) > budget:
                state = "over budget" if len(where) > budget else "within budget"
                print(f"  {rel}: {len(where)} (budget {budget}, {state})")
                for n, text in where:
                    print(f"    {n}: {text}")
            if len(where) > budget:
                failed = True
        for (k, rel), budget in sorted(allow.items()):
            have = len(files.get(rel, [])) if k == kind else None
            if have is not None and have < budget:
                print(f"  note: {rel} has {have} (budget {budget}): lower its budget")
    if failed:
        print("Ask the codec instead (codec/function_code.hpp, codec/mbap.hpp), or justify the "
              "site with a comment 'one-place: WHY' on it or the line above.", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
