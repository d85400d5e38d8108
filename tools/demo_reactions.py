#!/usr/bin/env python3
"""Reaction times of a recorded demo (OUT/demo.bag): the collision flag's onsets vs the zone-demanded ones.

Usage: tools/demo_reactions.py OUT/demo.bag

The bag holds no HighCmd (LCM), so the commanded velocity is taken from /cmd_vel (what the bridge
turns into HighCmds) at its receive time; the live demo measures on the A1's LCM stream.
"""

import math
import sys

import rosbag

from rbd_bringup.demo_report import StopOnsets, percentile, reaction_times


def main(path: str) -> None:
    """Print both metrics' stop count, p50, p99 for the bag at ``path``."""
    stops = StopOnsets()
    flag_onsets, prev, state = [], False, ""
    commands, velocities = [], []
    with rosbag.Bag(path) as bag:
        for topic, m, t in bag.read_messages(topics=["/rbd_lidar/state", "/rbd_controller/state", "/cmd_vel"]):
            if topic == "/cmd_vel":
                v = (m.linear.x, m.linear.y, m.angular.z)
                velocities.append((t.to_sec(), v))
                commands.append((t.to_sec(), max(math.hypot(v[0], v[1]), abs(v[2]))))
            elif topic == "/rbd_controller/state":
                state = m.data
            else:
                stamp, valid = m.header.stamp.to_sec(), not m.stale and not m.error
                v = next((v for tv, v in reversed(velocities) if tv <= stamp), (0.0, 0.0, 0.0))
                stops.update(stamp, m.collision, m.points, valid, v, state)
                if m.collision and not prev and valid:
                    flag_onsets.append(stamp)
                prev = m.collision
    for name, onsets in (("collision-flag onsets", flag_onsets), ("zone-demanded stops", stops.onsets)):
        r = reaction_times(onsets, commands)
        if r:
            print("%s: %d, p50 %.4f s, p99 %.4f s" % (name, len(r), percentile(r, 50), percentile(r, 99)))
        else:
            print("%s: none" % name)


if __name__ == "__main__":
    main(sys.argv[1])
