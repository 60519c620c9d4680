#!/usr/bin/python3
"""Interop check: pymodbus 3.0 (Debian) client against mbstorm's reference slave.

Exercises every function code pymodbus 3.0's client supports. Usage: interop_pymodbus.py PORT
Exits 0 when every check passes, 1 otherwise (each failure printed)."""
import socket
import sys

from pymodbus.client import ModbusTcpClient
from pymodbus.file_message import (FileRecord, ReadFifoQueueRequest, ReadFileRecordRequest,
                                   WriteFileRecordRequest)
from pymodbus.mei_message import ReadDeviceInformationRequest
from pymodbus.other_message import (GetCommEventCounterRequest, GetCommEventLogRequest,
                                    ReadExceptionStatusRequest, ReportSlaveIdRequest)
from pymodbus.diag_message import ReturnQueryDataRequest

failures = []


def check(name, condition, detail=""):
    print(("ok   " if condition else "FAIL ") + name + (f"  ({detail})" if detail else ""))
    if not condition:
        failures.append(name)


def ok(resp):
    return resp is not None and not resp.isError()


def raw_exchange(port, frame):
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall(frame)
        data = b""
        while len(data) < 6 or len(data) < 6 + int.from_bytes(data[4:6], "big"):
            chunk = s.recv(512)
            if not chunk:
                break
            data += chunk
        return data


def main(port):
    client = ModbusTcpClient("127.0.0.1", port=port, timeout=5)
    if not client.connect():
        print("FAIL cannot connect")
        return 1
    u = 1

    r = client.write_coil(10, True, slave=u)
    check("FC05 write single coil", ok(r))
    r = client.write_coils(20, [True, False, True, True, False, False, True, False, True], slave=u)
    check("FC0F write multiple coils", ok(r))
    r = client.read_coils(20, 9, slave=u)
    check("FC01 read coils", ok(r) and r.bits[:9] == [True, False, True, True, False, False, True,
                                                     False, True], getattr(r, "bits", r))
    r = client.read_coils(10, 1, slave=u)
    check("FC01 read back FC05", ok(r) and r.bits[0] is True)
    r = client.read_discrete_inputs(0, 16, slave=u)
    check("FC02 read discrete inputs", ok(r) and len(r.bits) >= 16)

    r = client.write_register(100, 0x1234, slave=u)
    check("FC06 write single register", ok(r))
    r = client.write_registers(200, [1, 2, 3, 0xFFFF], slave=u)
    check("FC10 write multiple registers", ok(r))
    r = client.read_holding_registers(200, 4, slave=u)
    check("FC03 read holding registers", ok(r) and r.registers == [1, 2, 3, 0xFFFF],
          getattr(r, "registers", r))
    r = client.read_holding_registers(100, 1, slave=u)
    check("FC03 read back FC06", ok(r) and r.registers == [0x1234])
    r = client.read_input_registers(0, 10, slave=u)
    check("FC04 read input registers", ok(r) and len(r.registers) == 10)

    r = client.mask_write_register(address=100, and_mask=0x00F2, or_mask=0x0025, slave=u)
    check("FC16 mask write register", ok(r))
    r = client.read_holding_registers(100, 1, slave=u)
    expected = (0x1234 & 0x00F2) | (0x0025 & ~0x00F2 & 0xFFFF)
    check("FC16 result", ok(r) and r.registers == [expected], getattr(r, "registers", r))

    r = client.readwrite_registers(read_address=300, read_count=2, write_address=300,
                                   write_registers=[7, 8], slave=u)
    check("FC17 read/write multiple registers", ok(r) and r.registers == [7, 8],
          getattr(r, "registers", r))

    # FIFO convention of the reference slave: register P = count, P+1.. = values.
    client.write_registers(400, [2, 11, 22], slave=u)
    r = client.execute(ReadFifoQueueRequest(400, unit=u))
    # pymodbus 3.0's ReadFifoQueueResponse.decode treats the FIFO count as a byte count
    # (spec v1.1b3 6.18: it is the number of registers) and so decodes no values: accept the
    # exchange here and check the values on the raw frame below.
    check("FC18 read FIFO queue (pymodbus exchange)", ok(r))
    raw = raw_exchange(port, bytes([0, 9, 0, 0, 0, 4, u, 0x18, 400 >> 8, 400 & 0xFF]))
    check("FC18 read FIFO queue (raw frame)",
          raw == bytes([0, 9, 0, 0, 0, 10, u, 0x18, 0, 6, 0, 2, 0, 11, 0, 22]), raw.hex())

    r = client.execute(WriteFileRecordRequest(
        records=[FileRecord(file_number=1, record_number=5, record_data=b"\x00\x01\xab\xcd")],
        unit=u))
    check("FC15 write file record", ok(r))
    r = client.execute(ReadFileRecordRequest(
        records=[FileRecord(file_number=1, record_number=5, record_length=2)], unit=u))
    check("FC14 read file record",
          ok(r) and len(r.records) == 1 and r.records[0].record_data == b"\x00\x01\xab\xcd",
          getattr(r, "records", r))

    r = client.execute(ReadExceptionStatusRequest(unit=u))
    check("FC07 read exception status", ok(r))
    r = client.execute(ReturnQueryDataRequest(0x1234, unit=u))
    check("FC08/00 return query data", ok(r) and list(r.message) == [0x1234],
          getattr(r, "message", r))
    r = client.execute(GetCommEventCounterRequest(unit=u))
    check("FC0B comm event counter", ok(r) and r.count > 0, getattr(r, "count", r))
    r = client.execute(GetCommEventLogRequest(unit=u))
    check("FC0C comm event log", ok(r) and r.message_count > 0, getattr(r, "message_count", r))
    r = client.execute(ReportSlaveIdRequest(unit=u))
    check("FC11 report server id", ok(r) and b"mbstorm" in bytes(r.identifier),
          getattr(r, "identifier", r))
    r = client.execute(ReadDeviceInformationRequest(read_code=1, object_id=0, unit=u))
    check("FC2B/0E read device identification", ok(r) and 0 in r.information and
          1 in r.information and 2 in r.information, getattr(r, "information", r))

    # Exceptions come back as exceptions.
    r = client.read_holding_registers(0, 126, slave=u)
    check("FC03 quantity 126 -> exception 03", r is not None and r.isError() and
          getattr(r, "exception_code", None) == 3, r)
    client.close()
    print(f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(int(sys.argv[1])))
