"""python-can's socketcand client as a peer of rise's socketcand+listen server.

Usage: python_can_socketcand_peer.py HOST PORT

Connects with can.Bus(interface="socketcand", channel="can0"), sends
0x123 [01 02 03] and the 29-bit 0x1ABCDEF0 [DE AD], then prints each frame
it receives as "RX <ID hex> <DATA hex>" until it has seen 5 frames with id
0x321 or 10 s have passed. Exit status 0 when it saw them, 1 otherwise.
"""
import sys
import time

import can

WANTED_ID = 0x321
WANTED_COUNT = 5


def main() -> int:
    host, port = sys.argv[1], int(sys.argv[2])
    bus = can.Bus(interface="socketcand", channel="can0", host=host, port=port)
    try:
        bus.send(can.Message(arbitration_id=0x123, is_extended_id=False, data=[1, 2, 3]))
        bus.send(can.Message(arbitration_id=0x1ABCDEF0, is_extended_id=True, data=[0xDE, 0xAD]))
        print("SENT 2", flush=True)
        seen = 0
        deadline = time.monotonic() + 10.0
        while seen < WANTED_COUNT and time.monotonic() < deadline:
            msg = bus.recv(timeout=0.5)
            if msg is None:
                continue
            print(f"RX {msg.arbitration_id:X} {bytes(msg.data).hex().upper()}", flush=True)
            if msg.arbitration_id == WANTED_ID:
                seen += 1
        return 0 if seen >= WANTED_COUNT else 1
    finally:
        bus.shutdown()


if __name__ == "__main__":
    sys.exit(main())
