#!/usr/bin/python3
"""Comparison peer: pymodbus 3.0 asyncio TCP server with 1000 of each table.

Usage: pymodbus_server.py [--seconds S]   prints "PORT <n>" once listening."""
import asyncio
import logging
import socket
import sys

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus.server import StartAsyncTcpServer


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


async def main(seconds):
    logging.disable(logging.CRITICAL)
    block = lambda: ModbusSequentialDataBlock(0, [0] * 1000)
    store = ModbusSlaveContext(di=block(), co=block(), hr=block(), ir=block())
    context = ModbusServerContext(slaves=store, single=True)
    port = free_port()
    server = await StartAsyncTcpServer(context, address=("127.0.0.1", port), defer_start=True)
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
        asyncio.run(main(secs))
    except (KeyboardInterrupt, asyncio.CancelledError):
        pass
