#!/usr/bin/python3
"""pymodbus 3.0's asyncio TCP server with 1000 of each table: the comparison peer of the benches
and the independent server of the interop tests.

Usage: pymodbus_server.py [--seconds S] [--framer socket|rtu] [--tls CERTDIR]
  --framer rtu   RTU frames on the TCP stream (RTU over TCP) instead of MBAP
  --tls CERTDIR  TLS (1.2 or later) with CERTDIR/server.pem and .key, asking for a client
                 certificate signed by CERTDIR/ca.pem. It keeps the SOCKET framer: pymodbus's
                 TLS framer drops the MBAP header (pymodbus#2014).
Prints "PORT <n>" once listening; runs S seconds (0 or none: until killed)."""
import asyncio
import logging
import socket
import ssl
import sys

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus.framer.socket_framer import ModbusSocketFramer
from pymodbus.server import StartAsyncTcpServer, StartAsyncTlsServer
from pymodbus.transaction import ModbusRtuFramer


def option(name, default):
    return sys.argv[sys.argv.index(name) + 1] if name in sys.argv else default


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def tls_context(certs):
    ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
    ctx.minimum_version = ssl.TLSVersion.TLSv1_2
    ctx.load_cert_chain(f"{certs}/server.pem", f"{certs}/server.key")
    ctx.load_verify_locations(f"{certs}/ca.pem")
    ctx.verify_mode = ssl.CERT_REQUIRED
    return ctx


async def main(seconds, framer, certs):
    logging.disable(logging.CRITICAL)
    block = lambda: ModbusSequentialDataBlock(0, [0] * 1000)
    store = ModbusSlaveContext(di=block(), co=block(), hr=block(), ir=block())
    context = ModbusServerContext(slaves=store, single=True)
    port = free_port()
    framer = ModbusRtuFramer if framer == "rtu" else ModbusSocketFramer
    if certs:
        server = await StartAsyncTlsServer(context, address=("127.0.0.1", port),
                                           sslctx=tls_context(certs), framer=framer,
                                           defer_start=True)
    else:
        server = await StartAsyncTcpServer(context, address=("127.0.0.1", port), framer=framer,
                                           defer_start=True)
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
    try:
        asyncio.run(main(float(option("--seconds", 0)), option("--framer", "socket"),
                         option("--tls", "")))
    except (KeyboardInterrupt, asyncio.CancelledError):
        pass
