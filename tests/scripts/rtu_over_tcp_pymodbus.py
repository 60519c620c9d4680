#!/usr/bin/python3
"""RTU over TCP with pymodbus 3.0 (Debian) as the independent peer (its server is
bench/peers/pymodbus_server.py --framer rtu).

  rtu_over_tcp_pymodbus.py client PORT   pymodbus's RTU-framer TCP client against a server on
                                         PORT: writes and reads back registers and coils, reads
                                         inputs, and expects exception 02 for a bad address.
Exits 0 when every check passes, 1 otherwise (each failure printed)."""
import sys

from pymodbus.transaction import ModbusRtuFramer


def client(port):
    from pymodbus.client import ModbusTcpClient
    failures = []

    def check(name, condition, detail=""):
        print(("ok   " if condition else "FAIL ") + name + (f"  ({detail})" if detail else ""))
        if not condition:
            failures.append(name)

    c = ModbusTcpClient("127.0.0.1", port=port, framer=ModbusRtuFramer, timeout=5)
    check("connect", c.connect())
    r = c.write_registers(100, [11, 22, 33], slave=1)
    check("FC16 write registers", r is not None and not r.isError(), r)
    r = c.read_holding_registers(100, 3, slave=1)
    check("FC03 read back", r is not None and not r.isError() and r.registers == [11, 22, 33], r)
    r = c.write_coil(7, True, slave=1)
    check("FC05 write coil", r is not None and not r.isError(), r)
    r = c.read_coils(7, 1, slave=1)
    check("FC01 read back", r is not None and not r.isError() and r.bits[0], r)
    r = c.read_input_registers(0, 10, slave=1)
    check("FC04 ten input registers", r is not None and not r.isError() and len(r.registers) == 10, r)
    r = c.read_holding_registers(65530, 10, slave=1)
    check("FC03 past the end: exception 02", r is not None and r.isError()
          and getattr(r, "exception_code", None) == 2, r)
    # Many in a row on one connection (RTU: one at a time).
    good = 0
    for i in range(200):
        r = c.read_holding_registers(i, 2, slave=1)
        good += r is not None and not r.isError()
    check("200 reads in a row", good == 200, f"{good} answered")
    c.close()
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(client(int(sys.argv[2])))
