#!/usr/bin/python3
"""Serial timing accuracy of `mbstorm serve --serial` on a pseudo-terminal, which has no
baud-rate timing of its own: an RTU master (this script) sends FC03 requests one at a time and
times, for each, the gap from the request's write to the answer's first byte. mbstorm serve
must keep the 3.5-character silence before it answers (t3.5: 2.0 ms at 19200 8E1, 1.75 ms
fixed above 19200): the gap minus t3.5 is the server's overshoot (scheduling and the pty).

Usage: serial_timing.py DEVICE BAUD COUNT   prints one line of percentiles in microseconds."""
import os
import select
import sys
import termios
import time
import tty


def crc16(data):
    crc = 0xFFFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return bytes([crc & 0xFF, crc >> 8])


def main(device, baud, count):
    fd = os.open(device, os.O_RDWR | os.O_NOCTTY)
    tty.setraw(fd)
    bits = 11  # 8E1: start, 8 data, parity, stop
    t35 = 1.75e-3 if baud > 19200 else 3.5 * bits / baud
    request = bytes([1, 3, 0, 0, 0, 1])
    request += crc16(request)
    gaps = []
    for _ in range(count):
        time.sleep(0.005)  # the master's own silence, generously
        termios.tcflush(fd, termios.TCIFLUSH)
        start = time.monotonic()
        os.write(fd, request)
        ready, _, _ = select.select([fd], [], [], 1.0)
        if not ready:
            print("no answer", file=sys.stderr)
            return 1
        gaps.append(time.monotonic() - start)
        got = b""
        while len(got) < 7:
            select.select([fd], [], [], 1.0)
            got += os.read(fd, 64)
    gaps.sort()
    pct = lambda p: gaps[min(len(gaps) - 1, int(p / 100 * len(gaps)))]
    under = sum(1 for g in gaps if g < t35)
    print(f"baud {baud}: t3.5 {t35 * 1e6:.0f} us; request-to-answer gap over {count}: "
          f"min {gaps[0] * 1e6:.0f} p50 {pct(50) * 1e6:.0f} p99 {pct(99) * 1e6:.0f} "
          f"max {gaps[-1] * 1e6:.0f} us; answers before t3.5: {under}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], int(sys.argv[2]), int(sys.argv[3])))
