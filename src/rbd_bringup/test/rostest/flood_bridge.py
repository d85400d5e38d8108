#!/usr/bin/env python3
"""Flood a rosbridge-protocol server from one WebSocket client until SIGINT/SIGTERM (test helper).

Usage: flood_bridge.py URL N. Publishes gestures and heartbeats (allowed by RoboDog's bridge
allow-list) and every 50th frame a 200 kB non-JSON frame, as fast as it can, never reading.
Runs in its own process so the flood does not starve the measuring test node (GIL). At the
end prints one JSON line: {"frames": ..., "garbage": ..., "reconnects": ..., "error": ...}.
"""

import json
import signal
import sys
import time

STATE = {"running": True}


def _stop(_sig, _frame):
    STATE["running"] = False


# before the (slow) websockets import: a stop request during start-up still ends cleanly
signal.signal(signal.SIGINT, _stop)
signal.signal(signal.SIGTERM, _stop)

from websockets.exceptions import WebSocketException  # noqa: E402
from websockets.sync.client import connect  # noqa: E402

GARBAGE = "{" + "x" * 200000  # a 200 kB frame that is not JSON


def frames(n):
    """The flood: advertise, then gesture, heartbeat, gesture, ... with garbage in between."""
    yield json.dumps({"op": "advertise", "topic": "/rbd_gestrec/gesture", "type": "std_msgs/String"})
    yield json.dumps({"op": "advertise", "topic": "/rbd_local/heartbeat", "type": "std_msgs/Header"})
    gesture = json.dumps({"op": "publish", "topic": "/rbd_gestrec/gesture", "msg": {"data": "wiggle"}})
    beat = json.dumps({"op": "publish", "topic": "/rbd_local/heartbeat", "msg": {"frame_id": "flood%d" % n}})
    i = 0
    while True:
        i += 1
        yield gesture
        yield beat
        if i % 50 == 0:
            yield GARBAGE


def main():
    """Flood until told to stop; print the counts."""
    url, n = sys.argv[1], int(sys.argv[2])
    state = STATE
    counts = {"frames": 0, "garbage": 0, "reconnects": 0, "error": None}
    while state["running"]:
        try:
            with connect(url, compression=None, max_size=None, open_timeout=15) as ws:
                for frame in frames(n):
                    if not state["running"]:
                        break
                    ws.send(frame)
                    counts["frames"] += 1
                    if frame is GARBAGE:
                        counts["garbage"] += 1
        except (OSError, WebSocketException) as err:
            counts["error"] = repr(err)
            counts["reconnects"] += 1
            time.sleep(0.1)
    print(json.dumps(counts), flush=True)


if __name__ == "__main__":
    main()
