#!/usr/bin/env python3
"""Screenshots for the README, taken for real under Xvfb.

RViz's audience view on the running simulated system, with a visitor standing in the collision
zone (intruding points in red).

Usage: tools/screenshots.py [OUT_DIR] (default docs/). Needs Xvfb and ImageMagick's `import`.
"""

import os
import signal
import socket
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def free_port():
    """A TCP port on 127.0.0.1 that is free right now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def free_display():
    """An X display number with no server."""
    for n in range(90, 200):
        if not os.path.exists("/tmp/.X%d-lock" % n) and not os.path.exists("/tmp/.X11-unix/X%d" % n):
            return n
    raise RuntimeError("no free X display")


def main():
    """Start Xvfb, the simulated system with RViz, place a visitor, capture the screen."""
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "docs")
    os.makedirs(out, exist_ok=True)
    disp = free_display()
    home = tempfile.mkdtemp(prefix="rbd-shot-home.")
    port = free_port()
    env = dict(os.environ, DISPLAY=":%d" % disp, ROS_MASTER_URI="http://127.0.0.1:%d" % port, ROS_HOME=home,
               ROS_IP="127.0.0.1", XDG_RUNTIME_DIR=home, LIBGL_ALWAYS_SOFTWARE="1")
    procs = [subprocess.Popen(["Xvfb", ":%d" % disp, "-screen", "0", "1280x720x24", "-nolisten", "tcp"],
                              start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        time.sleep(1.5)
        log = open(os.path.join(home, "launch.log"), "w")
        procs.append(subprocess.Popen(
            ["roslaunch", "-p", str(port), "rbd_bringup", "sim.launch", "rviz:=true", "lidar_columns:=1024",
             "bridge_port:=%d" % free_port()], env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True))
        time.sleep(20)
        call = ["rosservice", "call", "/rbd_sim/place_obstacle"]
        subprocess.run(call + ["{name: visitor, x: 0.55, y: 0.1, radius: 0.2, height: 1.7, remove: false}"], env=env,
                       check=True, stdout=subprocess.DEVNULL, timeout=30)
        time.sleep(8)
        png = os.path.join(out, "rviz_audience.png")
        subprocess.run(["import", "-display", ":%d" % disp, "-window", "root", png], env=env, check=True, timeout=60)
        print("written", png)
    finally:
        for p in reversed(procs):
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGINT)
                try:
                    p.wait(20)
                except subprocess.TimeoutExpired:
                    os.killpg(p.pid, signal.SIGKILL)


if __name__ == "__main__":
    main()
