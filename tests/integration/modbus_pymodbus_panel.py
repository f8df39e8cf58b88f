#!/usr/bin/python3
"""A rise-modbus-v1 console written with pymodbus (Debian python3-pymodbus,
3.0 API): serves the register map of firmware_protocol/README.md
("Modbus register map v1") on 127.0.0.1:PORT, unit 1, and runs the
firmware's 10 ms cycle: alive counter +1, uptime, CRC-16/MODBUS over
registers 0..16 (big endian). Coils written by the host are printed as
"leds 0x........" lines.

usage: modbus_pymodbus_panel.py PORT AXIS0 AXIS1 BUTTONS
"""
import asyncio
import struct
import sys
import time

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus_serve import serve


def crc16_modbus(data: bytes) -> int:
    crc = 0xFFFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


def input_registers(axes, counter, uptime_ms):
    regs = [a & 0xFFFF for a in axes]          # 0..5 axes, int16 two's complement
    regs += [0] * 6                            # 6..11 switches at position 0
    regs += [1, 1]                             # 12 Operational, 13 version 1
    regs += [(uptime_ms >> 16) & 0xFFFF, uptime_ms & 0xFFFF]  # 14..15, high word first
    regs += [counter & 0xFFFF]                 # 16 alive counter
    regs.append(crc16_modbus(struct.pack(">17H", *regs)))    # 17 CRC
    return regs


async def firmware(context, axes, buttons):
    slave = context[1]
    start = time.monotonic()
    counter = 0
    last_leds = None
    slave.setValues(2, 0, [(buttons >> i) & 1 for i in range(32)])
    while True:
        counter += 1
        uptime_ms = int((time.monotonic() - start) * 1000)
        slave.setValues(4, 0, input_registers(axes, counter, uptime_ms))
        leds = sum(1 << i for i, v in enumerate(slave.getValues(1, 0, 32)) if v)
        if leds != last_leds:
            print(f"leds 0x{leds:08x}", flush=True)
            last_leds = leds
        await asyncio.sleep(0.01)


async def main():
    port = int(sys.argv[1])
    axes = [int(sys.argv[2]), int(sys.argv[3]), 0, 0, 0, 0]
    buttons = int(sys.argv[4], 0)
    slave = ModbusSlaveContext(
        di=ModbusSequentialDataBlock(0, [0] * 32),
        co=ModbusSequentialDataBlock(0, [0] * 32),
        hr=ModbusSequentialDataBlock(0, [0] * 25),
        ir=ModbusSequentialDataBlock(0, [0] * 18),
        zero_mode=True)
    context = ModbusServerContext(slaves={1: slave}, single=False)
    asyncio.get_running_loop().create_task(firmware(context, axes, buttons))
    await serve(context, port)


if __name__ == "__main__":
    asyncio.run(main())
