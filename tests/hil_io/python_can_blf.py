#!/usr/bin/python3
"""python-can's BLF reader and writer, the peer of the BLF tests.

usage: python_can_blf.py dump FILE.blf
         one line per frame: ID EXTENDED REMOTE ERROR FD BRS ESI TIME_US DATA
         (TIME_US: microseconds since the epoch, the header's start time read
         in the local zone: run it with TZ=UTC; DATA hex or "-")
       python_can_blf.py write SOURCE_LOG FILE.blf [MAX_CONTAINER_BYTES]
         every frame of SOURCE_LOG (any format can.LogReader reads) to FILE.blf
       python_can_blf.py craft FILE.blf
         the objects BLFWriter never writes, laid out with python-can's own
         structs: CAN_FD_MESSAGE_64, CAN_MESSAGE2 with a version 2 header and
         10 us time units, CAN FD in CAN_FD_MESSAGE, CAN_ERROR_EXT
"""
import sys

import can

if sys.argv[1] == "dump":
    reader = can.BLFReader(sys.argv[2])
    for m in reader:
        data = m.data.hex() or "-"
        us = round(m.timestamp * 1e6)
        print(f"{m.arbitration_id:x} {int(m.is_extended_id)} {int(m.is_remote_frame)} "
              f"{int(m.is_error_frame)} {int(m.is_fd)} {int(m.bitrate_switch)} "
              f"{int(m.error_state_indicator)} {us} {data}")
elif sys.argv[1] == "write":
    extra = {"max_container_size": int(sys.argv[4])} if len(sys.argv) > 4 else {}
    with can.BLFWriter(sys.argv[3], **extra) as writer:
        for m in can.LogReader(sys.argv[2]):
            writer.on_message_received(m)
elif sys.argv[1] == "craft":
    import zlib
    from can.io import blf

    def obj(obj_type, payload, stamp, version=1, flags=blf.TIME_ONE_NANS):
        header = (blf.OBJ_HEADER_V1_STRUCT if version == 1 else blf.OBJ_HEADER_V2_STRUCT).pack(flags, 0, 0, stamp)
        base_size = blf.OBJ_HEADER_BASE_STRUCT.size
        size = base_size + len(header) + len(payload)
        base = blf.OBJ_HEADER_BASE_STRUCT.pack(b"LOBJ", base_size + len(header), version, size, obj_type)
        return base + header + payload + b"\0" * (size % 4)

    ext = blf.CAN_MSG_EXT
    objects = b"".join([
        obj(blf.CAN_FD_MESSAGE_64, blf.CAN_FD_MSG_64_STRUCT.pack(
            1, 15, 64, 0, ext | 0x1ABCDEF, 0, 0x1000 | 0x2000, 0, 0, 0, 0, 0, 1, 0, 0) + bytes(range(64)), 1000),
        obj(blf.CAN_FD_MESSAGE_64, blf.CAN_FD_MSG_64_STRUCT.pack(
            2, 9, 12, 0, 0x2A5, 0, 0x1000 | 0x4000, 0, 0, 0, 0, 0, 0, 0, 0) + bytes(range(100, 112)), 2000),
        obj(blf.CAN_MESSAGE2, blf.CAN_MSG_STRUCT.pack(3, 0x80, 4, 0x123, bytes(8)) + bytes(8), 345, 2, blf.TIME_TEN_MICS),
        obj(blf.CAN_MESSAGE2, blf.CAN_MSG_STRUCT.pack(3, 0, 3, 0x7FF, b"\x01\x02\x03" + bytes(5)) + bytes(8), 346, 2,
            blf.TIME_TEN_MICS),
        obj(blf.CAN_FD_MESSAGE, blf.CAN_FD_MSG_STRUCT.pack(1, 0, 9, 0x321, 0, 0, 0x1 | 0x4, 12, bytes(range(64))), 5000),
        obj(blf.CAN_ERROR_EXT, blf.CAN_ERROR_EXT_STRUCT.pack(1, 0, 0, 0, 0, 8, 0, 0x55, 0, bytes(8)), 6000),
    ])
    compressed = zlib.compress(objects)
    container = blf.LOG_CONTAINER_STRUCT.pack(blf.ZLIB_DEFLATE, len(objects)) + compressed
    size = blf.OBJ_HEADER_BASE_STRUCT.size + len(container)
    outer = blf.OBJ_HEADER_BASE_STRUCT.pack(b"LOBJ", 16, 1, size, blf.LOG_CONTAINER) + container + b"\0" * (size % 4)
    start = (2024, 5, 3, 2, 13, 14, 15, 678)  # 2024-05-02 13:14:15.678, a Thursday
    header = blf.FILE_HEADER_STRUCT.pack(b"LOGG", blf.FILE_HEADER_SIZE, 5, 0, 0, 0, 2, 6, 8, 1,
                                         blf.FILE_HEADER_SIZE + len(outer), len(objects), 6, 0, *start, *start)
    with open(sys.argv[2], "wb") as f:
        f.write(header + b"\0" * (blf.FILE_HEADER_SIZE - len(header)) + outer)
else:
    sys.exit(f"unknown mode {sys.argv[1]}")
