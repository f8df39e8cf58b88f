#!/usr/bin/python3
"""Third-party peer: python-can's socketcand client records what our console
emulator serves, as a candump log (`(sec.usec) can0 ID#DATA`).

usage: python_can_capture.py HOST PORT CHANNEL SECONDS OUT
"""
import sys
import time

import can

host, port, channel, seconds, out = sys.argv[1], int(sys.argv[2]), sys.argv[3], float(sys.argv[4]), sys.argv[5]
bus = can.Bus(interface="socketcand", channel=channel, host=host, port=port)
end = time.monotonic() + seconds
count = 0
with open(out, "w") as f:
    while time.monotonic() < end:
        msg = bus.recv(timeout=0.2)
        if msg is None:
            continue
        f.write("(%.6f) %s %03X#%s\n" % (msg.timestamp, channel, msg.arbitration_id, msg.data.hex().upper()))
        count += 1
bus.shutdown()
print("python-can received %d frames" % count)
