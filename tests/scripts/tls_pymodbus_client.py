#!/usr/bin/python3
"""Interop: pymodbus 3.0's TLS client (SOCKET framer: its TLS framer drops the MBAP header,
pymodbus#2014) against `mbstorm serve --transport tls`, with certificates made by the test.

Usage: tls_pymodbus_client.py PORT CERTDIR
Checks, each printed as "ok ..." or "FAIL ...": an Operator reads and writes; a Viewer reads,
and its write is answered with exception 01 (its role may not use function 06); a client
without a role, one signed by another CA, and one without a certificate are refused at the
handshake; TLS 1.2 and TLS 1.3 both work. Exit 1 on any FAIL."""
import asyncio
import logging
import ssl
import sys

from pymodbus.client import AsyncModbusTlsClient
from pymodbus.framer.socket_framer import ModbusSocketFramer

# The asyncio client: the synchronous ModbusTlsClient of pymodbus 3.0 select()s on the socket
# while the rest of a response may already sit decrypted in the SSL object, and misses it.
port = int(sys.argv[1])
certs = sys.argv[2]
failures = 0


def check(name, cond, detail=""):
    global failures
    print(("ok   " if cond else "FAIL ") + name + ("" if cond else f": {detail}"), flush=True)
    if not cond:
        failures += 1


def context(client, version=None):
    ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)
    ctx.load_verify_locations(f"{certs}/ca.pem")
    ctx.check_hostname = False
    if client:
        ctx.load_cert_chain(f"{certs}/{client}.pem", f"{certs}/{client}.key")
    if version is not None:
        ctx.minimum_version = ctx.maximum_version = version
    return ctx


async def connected(name, version=None):
    c = AsyncModbusTlsClient("127.0.0.1", port=port, framer=ModbusSocketFramer,
                             sslctx=context(name, version), timeout=3, retries=0,
                             reconnect_delay=0)
    await asyncio.wait_for(c.connect(), 5)
    return c


async def call(coro):
    try:
        return await asyncio.wait_for(coro, 5)
    except Exception as e:  # a refused session surfaces as any of ssl's or pymodbus's errors
        return e


def is_error(r):
    return isinstance(r, Exception) or r.isError()


async def refused(name):
    try:
        c = await connected(name)
    except Exception:
        return True
    try:
        r = await call(c.read_holding_registers(0, 1, slave=1))
        return is_error(r)
    finally:
        await c.close()


async def main():
    for label, version in (("TLS 1.3", ssl.TLSVersion.TLSv1_3),
                           ("TLS 1.2", ssl.TLSVersion.TLSv1_2)):
        op = await connected("operator", version)
        check(f"operator connects ({label})", op.connected)
        w = await call(op.write_registers(10, [1234, 5678], slave=1))
        check(f"operator writes ({label})", not is_error(w), w)
        r = await call(op.read_holding_registers(10, 2, slave=1))
        check(f"operator reads back ({label})",
              not is_error(r) and r.registers == [1234, 5678], r)
        await op.close()

    viewer = await connected("viewer")
    r = await call(viewer.read_holding_registers(10, 2, slave=1))
    check("viewer reads", not is_error(r) and r.registers == [1234, 5678], r)
    w = await call(viewer.write_register(10, 1, slave=1))
    check("viewer's write gets exception 01",
          not isinstance(w, Exception) and w.isError() and
          getattr(w, "exception_code", None) == 1, w)
    r = await call(viewer.read_holding_registers(10, 1, slave=1))
    check("viewer's session goes on after the exception",
          not is_error(r) and r.registers == [1234], r)
    await viewer.close()

    check("client without a role is refused", await refused("norole"))
    check("client of another CA is refused", await refused("rogue"))
    check("client without a certificate is refused", await refused(None))


logging.disable(logging.CRITICAL)
asyncio.run(main())
sys.exit(1 if failures else 0)
