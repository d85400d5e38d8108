#!/usr/bin/env python3
"""`make demo`: the whole RoboDog system in simulation with a scripted audience.

Starts a private ROS master and `rbd_bringup sim.launch`, plays the laptop app (rbd_local) for
the audience: gestures go through the app's own recognition pipeline (MediaPipe on clips in
which the real hand of an opencv-doc photo is moved along a generated gesture path) and through
the rosbridge-compatible server to the robot. After the four built-in tricks a visitor teaches a
new gesture (a checkmark, five shows) for the trick `bow` in teach mode and performs it; the
app sends the trick's name, which rbd_gestrec accepts because `bow` is a trick of
rbd_navigation. During the walk a person steps into the robot's way and leaves again. Then the
operator walks the robot 0.5 m ahead and turns it towards the lab's free half, sends `stroll`
(2 m out and back) and a bag is put down on the robot's way: it stops,
classifies the bag as static, steps back and walks around it, out and back (issue 17).
Everything safety-related is measured on the simulator's ground truth and on the command
stream the A1 receives over LCM.

Writes OUT/report.txt, OUT/report.json, OUT/run.png, OUT/demo.bag and OUT/recording (the robot's
inputs while it stands ready, before the release: `roslaunch rbd_bringup robot.launch
replay:=OUT/recording`). The pieces: demo_monitor.py (what is measured, the progress log),
demo_audience.py (the app's gesture pipeline shown real-photo clips) and demo_visitors.py (the
person who steps in, the bag, the operator).
"""

import argparse
import math
import os
import sys
import threading
import time

from demo_audience import GESTURE_INPUT, TAUGHT, Audience
from demo_monitor import Monitor, say, states_since, wait_done
from demo_visitors import drop_bag, intrude, turn

from rbd_testkit import RosEnv, free_port, restore_sigint, wait_for

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TRICKS = ["walk", "spin", "wiggle", "lie_down"]
OPERATOR_TRICKS = {"stroll"}  # sent as a command by the operator (no hand gesture of its own)
BAG_TOPICS = ["/rbd_sim/ground_truth", "/rbd_sim/obstacles", "/rbd_controller/state", "/rbd_controller/path_queue",
              "/rbd_pos_controller/status", "/rbd_lidar/state", "/cmd_vel", "/rbd_gestrec/gesture", "/scan",
              "/rbd_localization/pose", "/odometry/filtered", "/zed2/zed_node/pose", "/rbd_controller/path",
              "/rbd_controller/avoidance", "/rbd_controller/detour", "/rbd_controller/blocking_points"]


def main():
    """Run the demo; exit 0 when every trick completed with no contact."""
    restore_sigint()  # started in the background, roslaunch would inherit SIGINT ignored
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "demo-output"))
    ap.add_argument("--tricks", default=",".join(TRICKS + [TAUGHT[1], "stroll"]),
                    help="tricks to show; %s is taught first (teach mode); %s is sent by the operator"
                    % (TAUGHT[1], ", ".join(sorted(OPERATOR_TRICKS))))
    ap.add_argument("--intrude", default="walk", help="trick during which a person steps in ('' = none)")
    ap.add_argument("--bag", default="stroll", help="trick during which a bag is put down on the path ('' = none)")
    ap.add_argument("--columns", type=int, default=1024)
    ap.add_argument("--visual", action="store_true", help="open RViz (audience view) and the GUI")
    ap.add_argument("--record-seconds", type=float, default=6.0,
                    help="length of OUT/recording, the inputs for robot.launch replay:= (0 = none)")
    ap.add_argument("--trick-timeout", type=float, default=90.0)
    ap.add_argument("launch_args", nargs="*", help="extra sim.launch arguments, e.g. follow_localization:=true")
    args = ap.parse_args()
    tricks = [t for t in args.tricks.split(",") if t]
    os.makedirs(args.out, exist_ok=True)

    # A private master (own ROS_HOME, free port) that this process uses too; roslaunch.log in --out.
    env = RosEnv(log_dir=args.out, use_here=True, master_timeout=60.0, prefix="rbd-demo-home.")
    bridge_port = free_port()
    launch_args = ["rbd_bringup", "sim.launch", "lidar_columns:=%d" % args.columns, "bridge_port:=%d" % bridge_port,
                   "rviz:=%s" % str(args.visual).lower(), "gui:=%s" % str(args.visual).lower()] + args.launch_args
    say("starting the simulated system: roslaunch %s (master %s)" % (" ".join(launch_args), env.uri))
    env.launch(*launch_args, name="roslaunch")
    monitor = link = None
    try:
        import rospy

        rospy.init_node("demo_audience", disable_signals=True)
        wait_for(lambda: rospy.has_param("/rbd_sim/lcm_url"), 150.0, 0.2)
        monitor = Monitor(rospy.get_param("/rbd_sim/lcm_url"))
        env.start(["rosbag", "record", "-q", "-O", os.path.join(args.out, "demo.bag")] + BAG_TOPICS, name="rosbag")

        from rbd_local.link import RobotLink

        link = RobotLink(port=bridge_port).start()
        if not link.wait_connected(150.0):
            raise RuntimeError("laptop app could not reach the bridge on port %d" % bridge_port)
        say("laptop app connected to the bridge on port %d" % bridge_port)
        if not monitor.wait_state(("EMERGENCY_STOP",), 150.0):
            raise RuntimeError("controller did not come up in EMERGENCY_STOP")
        wait_for(lambda: monitor.pose is not None, 30.0, 0.1)
        # The robot's real inputs while it stands ready (as for a preflight), for
        # `robot.launch replay:=OUT/recording` (rbd_bringup README "Replay"; ~8 MB/s at 1024 columns).
        if args.record_seconds > 0:
            say("recording %.0f s of the robot's inputs (OUT/recording)" % args.record_seconds)
            code, out = env.run_to_exit(["rosrun", "rbd_bringup", "record", os.path.join(args.out, "recording"),
                                         "--duration", str(args.record_seconds)], timeout=args.record_seconds + 60.0)
            say(out.strip().splitlines()[-1] if code == 0 and out.strip() else "the recording failed: %s" % out[-500:])
        audience = Audience(link, os.path.join(ROOT, "rbd_local", ".cache"))

        say("operator releases the e-stop (GUI path: bridge -> /rbd_controller/em_stop)")
        ok, message = link.em_stop(False)
        if not ok:
            raise RuntimeError("e-stop release failed: %s" % message)
        monitor.wait_state(("WAITING_FOR_GESTURE",), 30.0)
        start_pose = monitor.pose
        t_start = time.monotonic()
        completed = []
        for i, trick in enumerate(tricks):
            if trick == TAUGHT[1]:
                audience.teach(seed=500)
            if trick == args.bag:
                # The lab's free half is behind the robot (a visitor walks a loop 2.8 m ahead of
                # home, inside the stop zone of the stroll's far pose): the operator walks it 0.5 m
                # ahead and turns it round (the far pose then keeps 1.1 m from the bin behind home);
                # the controller walks it home after the stroll (home = where the e-stop was released).
                c, s_ = math.cos(start_pose[2]), math.sin(start_pose[2])
                turn(monitor, start_pose[2] + math.pi, (start_pose[0] + 0.5 * c, start_pose[1] + 0.5 * s_))
            taken = False
            intruder = None
            for attempt in range(5):
                monitor.wait_state(("WAITING_FOR_GESTURE",), 30.0)
                n_log = len(monitor.state_log)  # a short trick can start and end while show() still runs
                if trick == args.intrude and intruder is None:
                    # the visitor watches from now on: the trick starts while the app still reads the clip
                    intruder = threading.Thread(target=intrude, args=(monitor, n_log), daemon=True)
                    intruder.start()
                if trick in OPERATOR_TRICKS:
                    say("the operator sends %r over the bridge" % trick)
                    link.send_gesture(trick)
                else:
                    audience.show(trick, seed=100 + 10 * i + attempt)
                if wait_for(lambda n=n_log: {"GENERATING_PATH", "EXECUTING"} & set(states_since(monitor, n)), 8.0):
                    taken = True
                    break
            if intruder is not None:
                intruder.join(60.0)
            if not taken:
                say("trick %s: the robot never took the gesture" % trick)
                continue
            if trick == args.bag:
                drop_bag(monitor)
            timeout = args.trick_timeout * (2.0 if trick == args.bag else 1.0)  # the way round the bag, twice
            seen = states_since(monitor, n_log)
            finished = "EXECUTING" in seen and seen[-1] == "WAITING_FOR_GESTURE"  # done before we looked
            if finished or (monitor.wait_state(("EXECUTING",), 10.0) and wait_done(monitor, timeout)):
                completed.append(trick)
                say("trick %s completed (%d/%d)" % (trick, len(completed), len(tricks)))
            else:
                say("trick %s did not complete" % trick)
            if trick == args.bag:
                turn(monitor, start_pose[2], start_pose[:2])  # a no-op when the controller walked it home
        duration = time.monotonic() - t_start
        time.sleep(1.0)
    finally:
        if link is not None:
            link.stop()
        if monitor is not None:
            monitor.close()
        env.close(timeout=20.0)

    from rbd_bringup.demo_report import build_report, plot_run, reaction_times, render_text, write_report

    with monitor.lock:
        report = build_report(tricks, completed, monitor.contacts.contacts, monitor.contacts.min_clearance,
                              monitor.state_log, start_pose, monitor.pose,
                              reaction_times(monitor.onsets, monitor.commands), 0.1, duration,
                              gesture_input=GESTURE_INPUT, avoidance_events=list(monitor.avoidance),
                              obstacle_contacts=monitor.box_contacts, min_obstacle_clearance=monitor.min_box_clearance)
        plot_run(monitor.path, monitor.people_log, monitor.stop_points, os.path.join(args.out, "run.png"),
                 boxes=list(monitor.boxes_seen.values()), detours=list(monitor.detours))
    write_report(report, args.out)
    print(render_text(report), flush=True)
    print("written: %s/{report.txt, report.json, run.png, demo.bag}" % args.out, flush=True)
    ok = (report["collisions_with_people"] == 0 and report["collisions_with_obstacles"] == 0
          and len(completed) == len(tricks))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
