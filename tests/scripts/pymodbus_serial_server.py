#!/usr/bin/python3
"""Interop peer: pymodbus 3.0's asyncio serial server (RTU or ASCII) on a tty, holding
registers 0..99 holding 1000 + their address.

Usage: pymodbus_serial_server.py DEVICE rtu|ascii [--seconds S]   prints "READY" once serving."""
import asyncio
import logging
import sys

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus.server import StartAsyncSerialServer
from pymodbus.transaction import ModbusAsciiFramer, ModbusRtuFramer


async def main(device, framing, seconds):
    logging.disable(logging.CRITICAL)
    # pymodbus's sequential blocks answer address a from list index a + 1 (its 1-based
    # convention); the leading 0 lines register a up with 1000 + a.
    hr = ModbusSequentialDataBlock(0, [0] + [1000 + a for a in range(100)])
    block = lambda: ModbusSequentialDataBlock(0, [0] * 101)
    store = ModbusSlaveContext(di=block(), co=block(), hr=hr, ir=block())
    context = ModbusServerContext(slaves=store, single=True)
    # No parity: pyserial's tcsetattr fails on a pseudo-terminal, which keeps no parity bit.
    framer = ModbusAsciiFramer if framing == "ascii" else ModbusRtuFramer
    server = await StartAsyncSerialServer(context, framer=framer, port=device, baudrate=19200,
                                          bytesize=8, parity="N", stopbits=1, defer_start=True)
    await server.start()  # opens the tty (serve_forever alone does not, in 3.0)
    task = asyncio.create_task(server.serve_forever())
    print("READY", flush=True)
    await asyncio.sleep(seconds if seconds > 0 else 10 ** 9)
    task.cancel()


if __name__ == "__main__":
    secs = float(sys.argv[sys.argv.index("--seconds") + 1]) if "--seconds" in sys.argv else 0
    try:
        asyncio.run(main(sys.argv[1], sys.argv[2], secs))
    except (KeyboardInterrupt, asyncio.CancelledError):
        pass
