#!/usr/bin/python3
"""python-can's BLF reader and writer, the peer of the BLF tests.

usage: python_can_blf.py dump FILE.blf
         one line per frame: ID EXTENDED REMOTE ERROR FD BRS ESI TIME_US DATA
         (TIME_US: microseconds since the epoch, the header's start time read
         in the local zone: run it with TZ=UTC; DATA hex or "-")
       python_can_blf.py write SOURCE_LOG FILE.blf [MAX_CONTAINER_BYTES]
         every frame of SOURCE_LOG (any format can.LogReader reads) to FILE.blf
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
else:
    sys.exit(f"unknown mode {sys.argv[1]}")
