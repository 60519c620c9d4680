#!/usr/bin/env python3
"""Writes the seed corpora of the framing harnesses (mbap_splitter, rtu, ascii) from the
framing test vectors (tests/codec/seed_vectors_framing_test.cpp and friends). One binary
file per input, named by the SHA-1 of its content. Run from anywhere:
    python3 fuzz/make_framing_corpus.py
"""
import hashlib
import pathlib

ROOT = pathlib.Path(__file__).resolve().parent.parent

TCP = [
    "00 01 00 00 00 06 01 01 00 02 00 08",
    "00 01 00 00 00 04 01 01 01 01",
    "00 01 00 00 00 06 01 02 03 01 04 00",
    "00 01 00 00 00 0D 01 04 0A 00 0C 00 00 00 00 00 00 00 00",
    "00 01 00 00 00 09 01 10 00 00 00 01 02 00 0F",
    "97 79 00 00 00 09 04 10 00 00 00 01 02 00 01",
    "00 04 00 01 00 06 01 03 00 00 00 01",      # protocol id 1
    "00 05 00 00 00 02 FF 07",                   # minimum length
    "00 06 00 00 00 FE 01 17" + " 5A" * 252,     # maximum length
]
TCP_BAD = ["00 07 00 00 00 00 01", "00 08 00 00 00 01 01", "00 09 00 00 00 FF 01 03"]

RTU = [
    "11 01 00 13 00 25 0E 84", "11 01 05 CD 6B B2 0E 1B 45 E6", "11 02 00 C4 00 16 BA A9",
    "11 02 03 AC DB 35 20 18", "11 03 00 6B 00 03 76 87", "11 03 06 00 6B 00 13 00 00 38 B9",
    "11 04 00 08 00 02 F2 99", "11 04 04 00 0A 00 0B 8B 80", "11 05 00 AC FF 00 4E 8B",
    "11 06 00 01 00 03 9A 9B", "11 0F 00 13 00 0A 02 CD 01 BF 0B", "11 0F 00 13 00 0A 26 99",
    "11 10 00 01 00 02 04 00 0A 01 02 C6 F0", "11 10 00 01 00 02 12 98",
    "01 03 00 6B 00 03 74 17", "01 03 06 02 2B 00 00 00 64 05 7A",
    "11 2B 0E 01 01 00 00 03 00 03 41 42 43 01 02 58 59 02 00",
    "11 18 00 06 00 02 01 B8 12 84", "11 83 02",
]

ASCII = [
    ":1103006B00037E\r\n", ":110100130025B6\r\n", ":110105CD6BB20E1BD6\r\n",
    ":11100001000204000A0102CB\r\n", ":0103006B00038E\r\n", ":010306022b0000006465\r\n",
    "01 03 00 00 00 0A C5 CD", "0x01:0x03", ":1103006B00037F\r\n",
]


def write(harness, blobs):
    out = ROOT / "fuzz" / "corpus" / harness
    out.mkdir(parents=True, exist_ok=True)
    for blob in blobs:
        (out / hashlib.sha1(blob).hexdigest()).write_bytes(blob)


def hx(s):
    return bytes.fromhex(s)


stream = b"".join(hx(f) for f in TCP)
splitter = [bytes([0x00, 0xFF]) + stream,           # one big chunk
            bytes([0x00, 0x01]) + stream,           # byte by byte
            bytes([0x02, 5, 0, 13]) + stream,       # 5, empty, 13, ...
            bytes([0x00, 0x07]) + stream + hx(TCP_BAD[0])]
splitter += [bytes([0x01, 3, 11]) + hx(TCP[0]) + hx(b) for b in TCP_BAD]
write("mbap_splitter", splitter)
write("rtu", [hx(f) for f in RTU])
write("ascii", [s.encode() for s in ASCII])
