#!/usr/bin/env python3
"""Screenshots for the README, taken for real under Xvfb.

- `rviz_audience.png`: RViz's audience view on the running simulated system, with a visitor
  standing in the collision zone (intruding points in red);
- `rviz_a1.png`: the same view close to the robot: the A1 model (rbd_description's URDF) with its
  legs from /joint_states, the OS1 on its back mount and the ZED2, from config/mounts.yaml;
- `gui_sim.png`: the laptop app's operator window (rbd_local's `rbd-gui`) connected through the
  bridge to the running simulated system while the robot executes the `walk` trick (state
  colour, controller state, next moves).

Usage: tools/screenshots.py [OUT_DIR] [--only rviz|a1|gui] (default docs/, all). Needs Xvfb and
ImageMagick's `import`.
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time

from rbd_testkit import free_port, restore_sigint, stop_process, wait_for_port

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def free_display():
    """An X display number with no server."""
    for n in range(90, 200):
        if not os.path.exists("/tmp/.X%d-lock" % n) and not os.path.exists("/tmp/.X11-unix/X%d" % n):
            return n
    raise RuntimeError("no free X display")


def closeup_config(home):
    """audience_sim.rviz with the camera 1.6 m from base_link (the robot fills the view)."""
    with open(os.path.join(ROOT, "src", "rbd_bringup", "rviz", "audience_sim.rviz")) as fh:
        text = fh.read()
    for old, new in (("      Distance: 7.5\n", "      Distance: 1.6\n"), ("      Pitch: 0.75\n", "      Pitch: 0.35\n"),
                     ("      Yaw: 3.6\n", "      Yaw: 2.5\n"), ("        X: 0.3\n", "        X: 0\n")):
        if old not in text:
            raise RuntimeError("audience_sim.rviz changed: %r not found" % old)
        text = text.replace(old, new)
    path = os.path.join(home, "a1_closeup.rviz")
    with open(path, "w") as fh:
        fh.write(text)
    return path


def shoot_rviz(out, closeup=False):
    """Start Xvfb, the simulated system with RViz, place a visitor, capture the screen."""
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
        view = ["rviz_config:=" + closeup_config(home)] if closeup else []
        procs.append(subprocess.Popen(
            ["roslaunch", "-p", str(port), "rbd_bringup", "sim.launch", "rviz:=true", "lidar_columns:=1024",
             "bridge_port:=%d" % free_port()] + view, env=env, stdout=log, stderr=subprocess.STDOUT,
            start_new_session=True))
        time.sleep(20)
        call = ["rosservice", "call", "/rbd_sim/place_obstacle"]
        subprocess.run(call + ["{name: visitor, x: 0.55, y: 0.1, radius: 0.2, height: 1.7, remove: false}"], env=env,
                       check=True, stdout=subprocess.DEVNULL, timeout=30)
        time.sleep(8)
        png = os.path.join(out, "rviz_a1.png" if closeup else "rviz_audience.png")
        subprocess.run(["import", "-display", ":%d" % disp, "-window", "root", png], env=env, check=True, timeout=60)
        print("written", png)
    finally:
        stop_all(procs)


def stop_all(procs):
    """SIGINT each process group (newest first), SIGKILL what does not stop."""
    for p in reversed(procs):
        stop_process(p, timeout=20.0)


def shoot_gui(out, delay=2.0):
    """The operator GUI on the running simulated system while the robot walks (under Xvfb)."""
    disp = free_display()
    home = tempfile.mkdtemp(prefix="rbd-shot-home.")
    port, bridge_port = free_port(), free_port()
    env = dict(os.environ, DISPLAY=":%d" % disp, ROS_MASTER_URI="http://127.0.0.1:%d" % port, ROS_HOME=home,
               ROS_IP="127.0.0.1", XDG_RUNTIME_DIR=home)
    env["PYTHONPATH"] = os.path.join(ROOT, "rbd_local", "src") + os.pathsep + env.get("PYTHONPATH", "")
    png = os.path.join(out, "gui_sim.png")
    procs = [subprocess.Popen(["Xvfb", ":%d" % disp, "-screen", "0", "1280x800x24", "-nolisten", "tcp"],
                              start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        time.sleep(1.5)
        log = open(os.path.join(home, "launch.log"), "w")
        procs.append(subprocess.Popen(
            ["roslaunch", "-p", str(port), "rbd_bringup", "sim.launch", "lidar_columns:=512",
             "bridge_port:=%d" % bridge_port], env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True))
        os.environ.update(ROS_MASTER_URI=env["ROS_MASTER_URI"], ROS_HOME=home, ROS_IP="127.0.0.1")
        import rospy
        from std_msgs.msg import String
        from std_srvs.srv import SetBool

        wait_for_port(port, 60.0)
        rospy.init_node("screenshot_operator", disable_signals=True)
        state = {"v": ""}
        rospy.Subscriber("/rbd_controller/state", String, lambda m: state.update(v=m.data), queue_size=10)
        gesture = rospy.Publisher("/rbd_gestrec/gesture", String, queue_size=1, latch=False)
        rospy.wait_for_service("/rbd_controller/em_stop", 60.0)
        time.sleep(3.0)
        rospy.ServiceProxy("/rbd_controller/em_stop", SetBool)(False)
        end = time.monotonic() + 15.0
        while state["v"] != "WAITING_FOR_GESTURE" and time.monotonic() < end:
            time.sleep(0.1)
        # A gesture arriving in WAITING_FOR_GESTURE is taken from the second one on: repeat it.
        end = time.monotonic() + 15.0
        while state["v"] not in ("GENERATING_PATH", "EXECUTING") and time.monotonic() < end:
            gesture.publish(String(data="walk"))
            time.sleep(0.5)
        print("robot state %s; operator window shoots in %.1f s" % (state["v"], delay))
        # The operator window connects to the bridge (latched state and path queue arrive at
        # once) and shoots itself after `delay` s, while the first moves are still queued.
        gui = subprocess.Popen([sys.executable, "-m", "rbd_local.gui_app", "--port", str(bridge_port), "--screenshot",
                                png, "--screenshot-delay", str(delay)], env=env, start_new_session=True)
        procs.append(gui)
        gui.wait(delay + 60)
        if gui.returncode != 0 or not os.path.exists(png):
            raise RuntimeError("rbd-gui did not write %s" % png)
        print("written", png)
    finally:
        stop_all(procs)


def main():
    """Take the screenshots asked for."""
    restore_sigint()  # started in the background, roslaunch would inherit SIGINT ignored
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", nargs="?", default=os.path.join(ROOT, "docs"))
    ap.add_argument("--only", choices=["rviz", "a1", "gui"])
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    if args.only in (None, "rviz"):
        shoot_rviz(args.out)
    if args.only in (None, "a1"):
        shoot_rviz(args.out, closeup=True)
    if args.only in (None, "gui"):
        shoot_gui(args.out)


if __name__ == "__main__":
    main()
