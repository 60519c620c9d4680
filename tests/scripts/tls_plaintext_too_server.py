#!/usr/bin/python3
"""A deliberately broken Modbus/TCP Security device for the fuzzer's tests: its TLS port also
serves plain Modbus/TCP (a connection whose first byte is not a TLS handshake record is served
without TLS). Answers every request with one holding register (FC 03) or exception 01.

Usage: tls_plaintext_too_server.py CERTDIR    prints "PORT <n>" once listening."""
import socket
import ssl
import struct
import sys
import threading


def serve(conn):
    buf = b""
    try:
        while True:
            while len(buf) < 7 or len(buf) < 6 + struct.unpack(">H", buf[4:6])[0]:
                data = conn.recv(4096)
                if not data:
                    return
                buf += data
            tid, _, length, unit = struct.unpack(">HHHB", buf[:7])
            fc = buf[7]
            buf = buf[6 + length:]
            pdu = bytes([3, 2, 0, 42]) if fc == 3 else bytes([fc | 0x80, 1])
            conn.sendall(struct.pack(">HHHB", tid, 0, len(pdu) + 1, unit) + pdu)
    except (OSError, ssl.SSLError):
        pass
    finally:
        conn.close()


def accept(raw, ctx):
    try:
        first = raw.recv(1, socket.MSG_PEEK)
        conn = ctx.wrap_socket(raw, server_side=True) if first == b"\x16" else raw
    except (OSError, ssl.SSLError):
        raw.close()
        return
    serve(conn)


def main(certs):
    ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
    ctx.load_cert_chain(f"{certs}/server.pem", f"{certs}/server.key")
    ctx.load_verify_locations(f"{certs}/ca.pem")
    ctx.verify_mode = ssl.CERT_REQUIRED
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(64)
    print(f"PORT {listener.getsockname()[1]}", flush=True)
    while True:
        raw, _ = listener.accept()
        threading.Thread(target=accept, args=(raw, ctx), daemon=True).start()


if __name__ == "__main__":
    try:
        main(sys.argv[1])
    except KeyboardInterrupt:
        pass
