#!/usr/bin/python3
"""A third-party Modbus PLC written with pymodbus (Debian python3-pymodbus,
3.0 API): serves unit 1 on 127.0.0.1:PORT, 32 coils, discrete inputs,
holding and input registers, 0-based addresses. Its inputs are what the
test writes into STATE_FILE, one table per line, re-read whenever the file
changes (replace it atomically):

    ir 0 65036 1000      input registers 0.. (uint16; 65036 is int16 -500)
    di 0 1 0             discrete inputs 0..
    hr 3 2               holding registers 3..
    co 8 1               coils 8..

What a master writes into coils 0..15 and holding registers 0..15 is
printed as "coil N = V" / "hr N = V" lines when it changes.

usage: modbus_pymodbus_plc.py PORT STATE_FILE
"""
import asyncio
import os
import sys

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus_serve import serve

TABLES = {"co": 1, "di": 2, "hr": 3, "ir": 4}  # the function codes that read them


def load(slave, path):
    with open(path, encoding="ascii") as f:
        for line in f:
            words = line.split()
            if len(words) >= 3 and words[0] in TABLES:
                values = [int(w, 0) & 0xFFFF for w in words[2:]]
                slave.setValues(TABLES[words[0]], int(words[1]), values)


async def plc(context, path):
    slave = context[1]
    stamp = None
    shown = {}
    while True:
        try:
            st = os.stat(path)
            if (st.st_mtime_ns, st.st_size, st.st_ino) != stamp:
                stamp = (st.st_mtime_ns, st.st_size, st.st_ino)
                load(slave, path)
        except FileNotFoundError:
            pass
        for name, fc in (("coil", 1), ("hr", 3)):
            for address, value in enumerate(slave.getValues(fc, 0, 16)):
                if shown.get((name, address), 0) != value:
                    print(f"{name} {address} = {int(value)}", flush=True)
                    shown[(name, address)] = value
        await asyncio.sleep(0.01)


async def main():
    port, path = int(sys.argv[1]), sys.argv[2]
    tables = {name: ModbusSequentialDataBlock(0, [0] * 32) for name in TABLES}
    context = ModbusServerContext(slaves={1: ModbusSlaveContext(**tables, zero_mode=True)}, single=False)
    load(context[1], path)
    asyncio.get_running_loop().create_task(plc(context, path))
    await serve(context, port)


if __name__ == "__main__":
    asyncio.run(main())
