#!/usr/bin/python3
"""Third-party reader: python-can's own candump log reader (can.LogReader
picks CanutilsLogReader for .log) reads a log rise-hild wrote; one line per
message in a fixed layout for the C++ test to compare with ours.

usage: python_can_read_log.py LOG OUT
"""
import sys

import can

log, out = sys.argv[1], sys.argv[2]
count = 0
with open(out, "w") as f:
    for m in can.LogReader(log):
        data = bytes(m.data or b"").hex().upper()
        f.write("%.6f %s %X ext=%d rtr=%d fd=%d brs=%d esi=%d err=%d rx=%d dlc=%d %s\n" % (
            m.timestamp, m.channel, m.arbitration_id, m.is_extended_id, m.is_remote_frame, m.is_fd,
            m.bitrate_switch, m.error_state_indicator, m.is_error_frame, m.is_rx, m.dlc, data or "-"))
        count += 1
print("python-can read %d messages from %s" % (count, log))
