#!/usr/bin/python3
"""Interop peer: pymodbus 3.0's asyncio TLS server with the SOCKET framer (its TLS framer drops
the MBAP header, pymodbus#2014), asking for a client certificate signed by CERTDIR/ca.pem.

Usage: tls_pymodbus_server.py CERTDIR [--seconds S]   prints "PORT <n>" once listening."""
import asyncio
import logging
import socket
import ssl
import sys

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus.framer.socket_framer import ModbusSocketFramer
from pymodbus.server import StartAsyncTlsServer


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


async def main(certs, seconds):
    logging.disable(logging.CRITICAL)
    block = lambda: ModbusSequentialDataBlock(0, [0] * 1000)
    store = ModbusSlaveContext(di=block(), co=block(), hr=block(), ir=block())
    context = ModbusServerContext(slaves=store, single=True)
    ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
    ctx.minimum_version = ssl.TLSVersion.TLSv1_2
    ctx.load_cert_chain(f"{certs}/server.pem", f"{certs}/server.key")
    ctx.load_verify_locations(f"{certs}/ca.pem")
    ctx.verify_mode = ssl.CERT_REQUIRED
    port = free_port()
    server = await StartAsyncTlsServer(context, address=("127.0.0.1", port), sslctx=ctx,
                                       framer=ModbusSocketFramer, defer_start=True)
    task = asyncio.create_task(server.serve_forever())
    for _ in range(200):  # wait until it listens
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=0.1):
                break
        except OSError:
            await asyncio.sleep(0.05)
    print(f"PORT {port}", flush=True)
    await asyncio.sleep(seconds if seconds > 0 else 10 ** 9)
    task.cancel()


if __name__ == "__main__":
    secs = float(sys.argv[sys.argv.index("--seconds") + 1]) if "--seconds" in sys.argv else 0
    try:
        asyncio.run(main(sys.argv[1], secs))
    except (KeyboardInterrupt, asyncio.CancelledError):
        pass
