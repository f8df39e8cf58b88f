#!/usr/bin/python3
"""Second reader for the log tests: python-can's LogReader counts the frames
of each file (all, error, remote, CAN FD), one line per file:
PATH N ERROR REMOTE FD.

usage: python_can_count_logs.py FILE...
"""
import sys

import can

for path in sys.argv[1:]:
    n = err = rtr = fd = 0
    for m in can.LogReader(path):
        n += 1
        err += m.is_error_frame
        rtr += m.is_remote_frame
        fd += m.is_fd
    print(path, n, err, rtr, fd)
