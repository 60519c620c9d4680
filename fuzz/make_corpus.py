#!/usr/bin/env python3
"""Writes the seed corpora of the PDU fuzz harnesses from the test vectors.

Reads the hex string literals in tests/codec/pdu_vectors.hpp (BEGIN/END REQUESTS and
RESPONSES blocks) plus a few boundary PDUs, and writes one binary file per PDU, named by
the SHA-1 of its content, into fuzz/corpus/<harness>/. Run from anywhere:
    python3 fuzz/make_corpus.py
"""
import hashlib
import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parent.parent
VECTORS = ROOT / "tests" / "codec" / "pdu_vectors.hpp"

# Boundary and malformed PDUs worth keeping in every corpus (spec v1.1b3 limits).
EXTRA = [
    "01 00 00 07 D1",        # FC01 quantity 2001
    "03 00 00 00 7E",        # FC03 quantity 126
    "03 FF FF 00 02",        # address overflow
    "05 00 00 12 34",        # bad coil value
    "0F 00 00 07 B0 F6" + " 00" * 246,   # FC0F 1968 coils
    "10 00 00 00 7B F6" + " 00" * 246,   # FC10 123 registers
    "17 00 00 00 7D 00 00 00 79 F2" + " 00" * 242,
    "18 00 40 00 1F" + " 00 01" * 31,   # FIFO 31 values (response)
    "14 07 06 00 00 00 00 00 01",        # file 0
    "2B 0E 05 00",           # bad device id code
    "08 00 13 00 00",        # reserved diagnostics sub-function
    "03 FA" + " 00" * 250,   # largest FC03 response
]


def block(text: str, name: str) -> list[str]:
    m = re.search(rf"// BEGIN {name}\n(.*?)// END {name}", text, re.S)
    return re.findall(r'"([0-9A-Fa-f ]*)"', m.group(1)) if m else []


def write(dirname: str, pdus: list[str]) -> None:
    out = ROOT / "fuzz" / "corpus" / dirname
    out.mkdir(parents=True, exist_ok=True)
    for h in pdus:
        data = bytes.fromhex(h)
        (out / hashlib.sha1(data).hexdigest()).write_bytes(data)


def main() -> None:
    text = VECTORS.read_text()
    requests = block(text, "REQUESTS")
    responses = block(text, "RESPONSES")
    write("request_pdu", requests + EXTRA)
    write("response_pdu", responses + EXTRA)
    write("pdu_roundtrip", requests + responses + EXTRA)


if __name__ == "__main__":
    main()
