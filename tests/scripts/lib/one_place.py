#!/usr/bin/env python3
"""Counts function-code knowledge and hand-made MBAP framing outside the codec.

Usage: one_place.py ROOT [--list]

Two facts have one owner each (docs/architecture.md): what a function code is (codec/, and
the slave that serves it) and how an MBAP frame is laid out (codec/). This finds places
elsewhere under src/ that still know them:

  function-code sites: a line naming a public function code as a literal (case 0x17:,
    fc == 0x16, function == 5, a 0x.. literal on a line about a function code, or a
    label like "0x05 write_single_coil" in text);
  MBAP sites: a line framing or cutting MBAP by hand (the length at byte 4, 6 + length,
    protocol id 0 at byte 2, function | 0x80).

A site is allowed when its line or the line above carries a comment "one-place: WHY". The
rest must fit the budget that tests/scripts/one_place_allow.txt gives its file (one line:
KIND PATH COUNT  # why). Exit 1 when a file has more sites than its budget, naming them.
"""
import pathlib
import re
import sys

PUBLIC = {0x01: "read_coils", 0x02: "read_discrete_inputs", 0x03: "read_holding_registers",
          0x04: "read_input_registers", 0x05: "write_single_coil",
          0x06: "write_single_register", 0x07: "read_exception_status", 0x08: "diagnostics",
          0x0B: "get_comm_event_counter", 0x0C: "get_comm_event_log",
          0x0F: "write_multiple_coils", 0x10: "write_multiple_registers",
          0x11: "report_server_id", 0x14: "read_file_record", 0x15: "write_file_record",
          0x16: "mask_write_register", 0x17: "read_write_multiple_registers",
          0x18: "read_fifo_queue", 0x2B: "encapsulated_interface"}
OWNERS_FC = ("src/codec/", "src/slave/")
OWNERS_MBAP = ("src/codec/",)

HEX = "|".join(f"0x{c:02X}" for c in PUBLIC) + "|" + "|".join(f"0x{c:02x}" for c in PUBLIC)
DEC = "|".join(str(c) for c in PUBLIC)
FC_PATTERNS = [
    re.compile(rf"\bcase\s+({HEX})\s*:"),
    re.compile(rf"\b(fc|function|function_code)\w*(\[\w+\])?\s*(==|!=|<=|>=)\s*({HEX}|{DEC})\b"),
    re.compile(rf"({HEX})\b[^;]*\b(fc|function)\b|\b(fc|function)\b[^;]*\b({HEX})\b"),
    re.compile(r"0x[0-9A-Fa-f]{2} (" + "|".join(PUBLIC.values()) + r")\b"),
    re.compile(rf"[({{]\s*({HEX})\s*,"),  # a PDU built from its function code: pdu5(0x17, ..
]
MBAP_PATTERNS = [
    re.compile(r"\b6u?\s*\+\s*[\w.>-]*length\b|\blength\s*\+\s*6u?\b"),
    re.compile(r"load_be16\(\s*[\w.]+\s*\+\s*4\s*\)"),
    re.compile(r"store_be16\(\s*[\w.]+\s*\+\s*2\s*,\s*0\s*\)"),
    re.compile(r"\|\s*0x80\b"),
]
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
            for kind, owners, patterns in (("fc", OWNERS_FC, FC_PATTERNS),
                                           ("mbap", OWNERS_MBAP, MBAP_PATTERNS)):
                if rel.startswith(owners):
                    continue
                if any(p.search(code) for p in patterns):
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
