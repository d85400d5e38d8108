#!/usr/bin/env python3
"""Save the map, restart in it with the robot placed away from home, converge, drive loops (issue 29).

On the seeded simulator with the whole localization (``sim_localization.launch``), one private
master for both runs:

1. Mapping run: the robot starts at ``first_start`` (world) and stands until the map's walls are
   static; ``rosrun rbd_localization save_map DIR NAME`` saves it; the stack is shut down.
2. Localization run: ``map:=DIR/NAME.yaml`` with the robot placed at ``place`` (relative to home,
   the first run's start). Measured on ground truth (world, mapped into the map frame through
   ``first_start``) against /rbd_localization/pose (map): the time from the first sensor data until
   the error is <= 0.05 m / 2 deg for good, when /rbd_localization/localized turned true (and
   that it was false before), preflight's "Localized in the map" line once localized.
   Optionally (``far_check``), before it: the whole system (rbd_bringup ``sim.launch``) placed at
   each of ``FAR_PLACES`` from home, where the robot must not localize (outside the start search;
   or outside it with its near 180-degree twin inside it): ``localized`` stays false, the
   controller refuses the gesture "spin" after the e-stop is released (its warning, no state
   change, no motion) and preflight's line FAILs.
3. Loops: the robot walks home and round the thesis path ``loops`` times, steered on
   /rbd_localization/pose (sim_loops.py's steering, ``steer="corrected"``, each loop settled
   back onto home after its last turn, which creeps); each loop's end is compared with its start
   on ground truth and with the localization's pose.
0. Optionally (``crowd_seconds`` > 0), in the mapping run: a crowd of five person-sized cylinders
   (``/rbd_sim/place_obstacle``) stands around the robot from its start for that long, then goes;
   the saved map is read with map_server's semantics and the cells they stood on are checked.
4. Optionally (``box_seconds`` > 0): a box left in front of the robot for that long, then the map
   is saved again and compared with the loaded one cell by cell (map_server semantics).

``run()`` returns a JSON-able report; ``main()`` writes it:
    rosrun rbd_localization map_restart.py --loops 10 --out /tmp/map_restart
(it starts its own master; run it under ``flock /tmp/rbd-sim.lock`` on a shared machine).
"""

import argparse
import json
import math
import os
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import sim_loops  # noqa: E402

#: Issue 29's bounds: a start up to 1.0 m / 45 deg from home converges to these within 5 s.
CONVERGED_M, CONVERGED_DEG, CONVERGE_WITHIN_S = 0.05, 2.0, 5.0
#: The brief's placement: 0.8 m / 40 deg from home (x, y [m], yaw [rad] relative to home).
DEFAULT_PLACE = (-0.8 * math.cos(math.radians(45.0)), 0.8 * math.sin(math.radians(45.0)), math.radians(40.0))
#: Placements where the robot must not localize (report key: (x, y [m], yaw [rad]) from home), clear
#: of the lab's people and furniture (the collision zone stays free). "far": outside the start
#: search (search_translation 1.2 m / search_rotation 0.9 rad), 1.96 m from home, turned 90 deg.
#: "twin": 2.0 m / 150 deg from home, outside the search, but the lab's walls are almost
#: point-symmetric and the pose's near 180-degree twin (0.4, 1.2, -30 deg) lies inside it: before
#: the start search's ambiguity check the search took the twin and reported localized 2.7 m /
#: 180 deg off (rbd_localization README "On the simulator").
FAR_PLACES = (("far", (-1.9, 0.5, -math.pi / 2)), ("twin", (1.6, -1.2, math.radians(150.0))))
#: s the far run waits for a localization that must not come.
FAR_WAIT_S = 10.0
#: s the mapping run stands before saving: the walls must stay occupied for static_time (10 s).
MAPPING_STAND_S = 16.0
#: The crowd at start (crowd_seconds > 0): (x, y) around home [m] (home frame), radius 0.25 m. Kept
#: off the lab's people paths; 1.0-1.4 m from the robot, as visitors around a starting robot.
CROWD = ((1.2, 0.3), (0.5, 1.1), (-1.0, 0.7), (-1.1, -0.5), (0.3, -1.2))
CROWD_RADIUS = 0.25
#: s the mapping run stands after the crowd left: static_time (10 s) + clearing.
AFTER_CROWD_S = 15.0
#: s the localization run stands (measuring convergence) before the loops start.
STAND_S = 12.0


def compose(a, b):
    """Pose b (x, y, yaw) given in the frame of pose a, in a's parent frame."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], sim_loops.wrap(a[2] + b[2])


def converge_time(samples, t0, pos_tol=CONVERGED_M, yaw_tol_deg=CONVERGED_DEG):
    """Seconds from t0 after which every sample stays within the bounds (None: never by the last one).

    samples: [(time [s], position error [m], yaw error [deg])] in time order.
    """
    t_conv = None
    for t, pos, yaw in samples:
        if pos <= pos_tol and yaw <= yaw_tol_deg:
            if t_conv is None:
                t_conv = t
        else:
            t_conv = None
    return None if t_conv is None else t_conv - t0


class Watch:
    """Localization run: pose error against the stamp-matched truth, localized flag, first sensor time."""

    def __init__(self, runner):
        import rospy
        from geometry_msgs.msg import PoseStamped
        from sensor_msgs.msg import Imu
        from std_msgs.msg import Bool

        from rbd_geometry.rotation import yaw_of

        self.r = runner
        self.yaw_of = yaw_of
        self.lock = threading.Lock()
        self.first_sensor = None
        self.samples = []  # (stamp, pos err, yaw err deg)
        self.localized = []  # (receive time, value)
        self.subs = [rospy.Subscriber("/ouster/imu", Imu, self.on_imu, queue_size=5),
                     rospy.Subscriber("/rbd_localization/pose", PoseStamped, self.on_pose, queue_size=20),
                     rospy.Subscriber("/rbd_localization/localized", Bool, self.on_localized, queue_size=5)]

    def on_imu(self, msg):
        with self.lock:
            if self.first_sensor is None:
                self.first_sensor = msg.header.stamp.to_sec()

    def on_pose(self, msg):
        stamp = msg.header.stamp.to_sec()
        with self.r.lock:
            truth = self.r.truth_at(stamp)
        if truth is None:
            return
        est = (msg.pose.position.x, msg.pose.position.y, self.yaw_of(msg.pose.orientation))
        err = (math.hypot(est[0] - truth[0], est[1] - truth[1]), abs(math.degrees(sim_loops.wrap(est[2] - truth[2]))))
        with self.lock:
            self.samples.append((stamp, err[0], err[1]))

    def on_localized(self, msg):
        import rospy

        with self.lock:
            self.localized.append((rospy.get_time(), bool(msg.data)))

    def close(self):
        for s in self.subs:
            s.unregister()


def preflight_localized_row(env):
    """Run preflight once (2 s) and return its "Localized in the map" row (dict) or the output."""
    code, out = env.run_to_exit(["rosrun", "rbd_preflight", "preflight", "--json", "--no-lcm", "--no-clocks",
                                 "--duration", "2"], timeout=60.0)
    try:
        start = 0 if out.startswith("{") else out.index("\n{") + 1  # log lines may come first
        rows = json.loads(out[start:out.rindex("}") + 1])["rows"]
    except (ValueError, KeyError):
        return {"error": out[-2000:], "exit": code}
    for row in rows:
        if "Localized in the map" in json.dumps(row):
            return row
    return {"error": "no 'Localized in the map' row", "rows": rows}


def refused_gesture(rospy, runner):
    """Release the e-stop, send the gesture "spin" while not localized; what the controller did.

    Returns {"states": states seen, "refusals": its warnings naming the gesture, "moved": metres
    the robot moved on ground truth from the gesture until 5 s after it}.
    """
    from rosgraph_msgs.msg import Log
    from std_msgs.msg import String
    from std_srvs.srv import SetBool

    states, refusals = [], []
    subs = [rospy.Subscriber("/rbd_controller/state", String, lambda m: states.append(m.data), queue_size=20),
            rospy.Subscriber("/rosout", Log, lambda m: refusals.append(m.msg) if "refusing gesture" in m.msg
                             else None, queue_size=100)]
    gesture = rospy.Publisher("/rbd_gestrec/gesture", String, queue_size=1)
    rospy.wait_for_service("/rbd_controller/em_stop", 60.0)
    wait_for(lambda: "EMERGENCY_STOP" in states, 60.0, "the controller in EMERGENCY_STOP")
    rospy.ServiceProxy("/rbd_controller/em_stop", SetBool)(False)
    wait_for(lambda: states and states[-1] == "WAITING_FOR_GESTURE", 30.0, "WAITING_FOR_GESTURE")
    with runner.lock:
        start = runner.truth
    n_states = len(states)
    for _ in range(3):
        gesture.publish(String("spin"))
        rospy.sleep(1.0)
    rospy.sleep(3.0)
    with runner.lock:
        end = runner.truth
    for sub in subs:
        sub.unregister()
    return {"states": list(states), "states_after_gesture": states[n_states:], "refusals": list(refusals),
            "moved": math.hypot(end[0] - start[0], end[1] - start[1])}


def never_localized_run(env, rospy, world, seed, columns, first_start, map_file, place, name):
    """The whole system (rbd_bringup sim.launch, the controller too) in the map, placed where it must
    not localize (place: from home): the controller's answer to "spin", preflight's line, the
    latched ``localized`` values and the pose error at the end (dict)."""
    from rbd_testkit import free_port
    from rbd_testkit.process import stop_process

    far = compose(first_start, place)
    runner = sim_loops.Runner(map_origin=first_start)
    watch = Watch(runner)
    stack = env.launch("rbd_bringup", "sim.launch", "world:=%s" % world, "seed:=%d" % seed,
                       "lidar_columns:=%d" % columns, "map:=%s" % map_file, "bridge_port:=%d" % free_port(),
                       "robot_x:=%.6f" % far[0], "robot_y:=%.6f" % far[1], "robot_yaw:=%.6f" % far[2], name=name)
    t = time.monotonic()
    try:
        if not runner.wait_ready(120.0):
            raise RuntimeError("%s: no ground truth / pose / odometry\n%s" % (name, env.tails()))
        out = {"place_from_home": [place[0], place[1], math.degrees(place[2])]}
        out["gesture"] = refused_gesture(rospy, runner)
        rospy.sleep(max(0.0, FAR_WAIT_S - 5.0))
        out["preflight_localized"] = preflight_localized_row(env)
        with watch.lock:
            out["localized_values"] = [v for _, v in watch.localized]
            last = watch.samples[-1] if watch.samples else None
        out["last_error"] = None if last is None else [last[1], last[2]]
    finally:
        watch.close()
        stop_process(stack, timeout=20.0)
    out["run_s"] = time.monotonic() - t
    return out


def save_map(env, directory, name):
    """rosrun rbd_localization save_map DIR NAME; returns (exit code, output)."""
    return env.run_to_exit(["rosrun", "rbd_localization", "save_map", directory, name, "--timeout", "30"],
                           timeout=90.0)


def launch(env, name, world, seed, columns, pose, map_file=""):
    """Start sim_localization.launch with the robot at pose (world)."""
    return env.launch(os.path.join(HERE, "sim_localization.launch"), "world:=%s" % world, "seed:=%d" % seed,
                      "lidar_columns:=%d" % columns, "map:=%s" % map_file, "robot_x:=%.6f" % pose[0],
                      "robot_y:=%.6f" % pose[1], "robot_yaw:=%.6f" % pose[2], name=name)


def wait_for(predicate, timeout, what):
    """rbd_testkit's wait_for, every 0.1 s; WaitTimeoutError naming what after timeout s."""
    import rbd_testkit

    return rbd_testkit.wait_for(predicate, timeout, 0.1, what=what)


def compare_maps(a_yaml, b_yaml):
    """Cell-by-cell comparison of two map_server maps of the same geometry (occupied/free counts)."""
    from map_correction_test import read_map_server

    occ_a, free_a, _ = read_map_server(a_yaml)
    occ_b, free_b, _ = read_map_server(b_yaml)
    if occ_a.shape != occ_b.shape:
        return {"same_shape": False, "shapes": [list(occ_a.shape), list(occ_b.shape)]}
    return {"same_shape": True, "occupied": int(occ_a.sum()), "free": int(free_a.sum()),
            "occupied_changed": int((occ_a != occ_b).sum()), "free_changed": int((free_a != free_b).sum())}


def crowd_cells(map_yaml, crowd_world):
    """Per crowd member: cells of its footprint in a saved map (map_server semantics): occupied / free / all."""
    import numpy as np
    from map_correction_test import read_map_server

    occ, free, xy = read_map_server(map_yaml)
    rows, cols = np.indices(occ.shape)
    x, y = xy((rows, cols))
    out = []
    for cx, cy in crowd_world:
        disk = np.hypot(x - cx, y - cy) <= CROWD_RADIUS
        near = np.hypot(x - cx, y - cy) <= CROWD_RADIUS + 0.1
        out.append({"xy": [cx, cy], "cells": int(disk.sum()), "occupied": int((occ & near).sum()),
                    "free": int((free & disk).sum())})
    return out


def grid_occupied_near(grid, points, radius):
    """Occupied cells (value >= 65, map_server's occupied_thresh) of an OccupancyGrid within radius of each point."""
    import numpy as np

    info = grid.info
    data = np.asarray(grid.data, dtype=np.int16).reshape(info.height, info.width)
    rows, cols = np.indices(data.shape)
    # the node's grid is axis-aligned (origin orientation identity)
    x = info.origin.position.x + (cols + 0.5) * info.resolution
    y = info.origin.position.y + (rows + 0.5) * info.resolution
    return [int(((data >= 65) & (np.hypot(x - px, y - py) <= radius)).sum()) for px, py in points]


#: Height bands [m above the floor] for comparing the saved map with the world. The map correction
#: slices the cloud 0.0-0.4 m above base_link (0.28 m above the floor on the A1): an occupied cell
#: must lie near a shape reaching into the slice (with 0.08 m for the body's pitch and the sensor
#: noise), and no cell may be free inside a shape that fills the slice's middle (a desk top at
#: 0.68-0.75 m is seen under, not through).
SLICE_ANY = (0.20, 0.76)
SLICE_CORE = (0.38, 0.58)


def shape_distance(boxes, cylinders, pts, z_lo, z_hi):
    """Signed distance [m] of points (N x 2, world) to the nearest footprint edge of the shapes
    reaching into [z_lo, z_hi] (negative inside one); inf without such a shape."""
    import numpy as np

    best = np.full(len(pts), np.inf)
    for b in boxes:
        if b.z1 < z_lo or b.z0 > z_hi:
            continue
        c, s = math.cos(b.yaw), math.sin(b.yaw)
        dx, dy = pts[:, 0] - b.cx, pts[:, 1] - b.cy
        qx, qy = np.abs(c * dx + s * dy) - b.hx, np.abs(-s * dx + c * dy) - b.hy
        d = np.hypot(np.maximum(qx, 0.0), np.maximum(qy, 0.0)) + np.minimum(np.maximum(qx, qy), 0.0)
        best = np.where(np.abs(d) < np.abs(best), d, best)
    for cyl in cylinders:
        if cyl.z1 < z_lo or cyl.z0 > z_hi:
            continue
        d = np.hypot(pts[:, 0] - cyl.cx, pts[:, 1] - cyl.cy) - cyl.radius
        best = np.where(np.abs(d) < np.abs(best), d, best)
    return best


def saved_vs_world(map_yaml, world_name, map_origin):
    """The saved map, read with map_server's semantics, against the simulator's static world.

    map_origin: the map frame's pose in the world (the mapping run's start). Returns the share of
    occupied cells within 0.1 m of a shape's footprint edge (and the farthest ones), the free cells
    deeper than 0.05 m inside a shape, and the occupied cells along each wall.
    """
    import numpy as np
    import rospkg
    from map_correction_test import read_map_server

    from rbd_sim.world_file import load_world, resolve_world_path

    world = load_world(resolve_world_path(world_name, os.path.join(rospkg.RosPack().get_path("rbd_sim"), "worlds")))
    occ, free, xy = read_map_server(map_yaml)
    c, s = math.cos(map_origin[2]), math.sin(map_origin[2])

    def in_world(mask):
        mx, my = xy(np.nonzero(mask))
        return np.stack([map_origin[0] + c * mx - s * my, map_origin[1] + s * mx + c * my], axis=1)

    po, pf = in_world(occ), in_world(free)
    d_occ = shape_distance(world.boxes, world.cylinders, po, *SLICE_ANY)
    d_free = shape_distance(world.boxes, world.cylinders, pf, *SLICE_CORE)
    far = np.argsort(-np.abs(d_occ))[:5]
    walls = [b for b in world.boxes if b.name.startswith("wall")]
    return {"occupied": int(len(po)), "free": int(len(pf)),
            "occupied_near_shape": float(np.mean(np.abs(d_occ) <= 0.1)) if len(po) else 0.0,
            "farthest_occupied": [[round(float(po[i, 0]), 3), round(float(po[i, 1]), 3), round(float(d_occ[i]), 3)]
                                  for i in far],
            "free_inside_shape": int(np.sum(d_free < -0.05)),
            "wall_cells": {b.name: int(np.sum(np.abs(shape_distance([b], [], po, -1e9, 1e9)) <= 0.1)) for b in walls}}


def classifier_sees(grid, points, radius):
    """Per point: the places within radius (0.05 m apart) that rbd_controller's avoidance reads as
    occupied in this /map (its GridMap from the OccupancyGrid and the lookup its classification
    makes, rbd_controller.perception.Perception.classify)."""
    import numpy as np

    from rbd_controller.detour import GridMap

    info = grid.info
    gm = GridMap.from_occupancy(grid.data, info.width, info.height,
                                (info.origin.position.x, info.origin.position.y), info.resolution)
    steps = np.arange(-radius, radius + 1e-9, 0.05)
    offsets = [(dx, dy) for dx in steps for dy in steps if math.hypot(dx, dy) <= radius]
    return [sum(gm.is_occupied(px + dx, py + dy) for dx, dy in offsets) for px, py in points]


def place_crowd(rospy, crowd_world, remove=False):
    """Put the crowd's cylinders into the simulated world (or take them away)."""
    from rbd_msgs.srv import PlaceObstacle

    rospy.wait_for_service("/rbd_sim/place_obstacle", 60.0)
    place = rospy.ServiceProxy("/rbd_sim/place_obstacle", PlaceObstacle)
    for i, (cx, cy) in enumerate(crowd_world):
        res = place(name="crowd_at_start_%d" % i, x=cx, y=cy, radius=CROWD_RADIUS, height=1.75, remove=remove)
        if not res.success:
            raise RuntimeError("place_obstacle: %s" % res.message)


def run(out_dir, loops=1, world="lab", seed=1, columns=512, first_start=(0.0, 0.0, 0.0), place=DEFAULT_PLACE,
        box_seconds=0.0, crowd_seconds=0.0, far_check=False, log_dir=None):
    """The whole experiment (see the module docstring); returns the report (dict)."""
    from rbd_testkit import RosEnv, restore_sigint
    from rbd_testkit.process import stop_process

    restore_sigint()
    os.makedirs(out_dir, exist_ok=True)
    report = {"world": world, "seed": seed, "columns": columns, "first_start": list(first_start),
              "place_from_home": [place[0], place[1], math.degrees(place[2])]}
    env = RosEnv(log_dir=log_dir or out_dir, use_here=True, master_timeout=60.0, prefix="rbd-map-restart.")
    try:
        import rospy

        rospy.init_node("map_restart", disable_signals=True)
        # --- 1. mapping run -----------------------------------------------------------------------
        t = time.monotonic()
        stack = launch(env, "mapping_run", world, seed, columns, first_start)
        crowd_world = [compose(first_start, (cx, cy, 0.0))[:2] for cx, cy in CROWD]
        if crowd_seconds > 0:  # there before the first scan: placed as soon as the world serves
            place_crowd(rospy, crowd_world)
            report["crowd"] = {"placed_at": rospy.get_time(), "seconds": crowd_seconds}
        runner = sim_loops.Runner(map_origin=first_start, steer="corrected")
        if not runner.wait_ready(120.0):
            raise RuntimeError("mapping run: no ground truth / pose / odometry\n" + env.tails())
        if crowd_seconds > 0:
            from nav_msgs.msg import OccupancyGrid

            grids = []
            map_sub = rospy.Subscriber("/map", OccupancyGrid, grids.append, queue_size=2)
            report["crowd"]["first_pose_at"] = rospy.get_time()
            rospy.sleep(crowd_seconds)
            map_sub.unregister()
            # the working map while they stood (map frame == home: the first start is the map origin)
            crowd_map = [(cx, cy) for cx, cy in CROWD]
            report["crowd"]["working_map_occupied"] = grid_occupied_near(grids[-1], crowd_map, CROWD_RADIUS + 0.1) \
                if grids else None
            place_crowd(rospy, crowd_world, remove=True)
            rospy.sleep(AFTER_CROWD_S)
            # the working /map now, as the avoidance's classification reads it (a map published after the wait)
            after, since = [], rospy.get_time()
            map_sub = rospy.Subscriber("/map", OccupancyGrid, after.append, queue_size=2)
            wait_for(lambda: after and after[-1].header.stamp.to_sec() >= since, 15.0, "a /map after the crowd left")
            map_sub.unregister()
            report["crowd"]["classifier_occupied"] = classifier_sees(after[-1], crowd_map, CROWD_RADIUS)
        else:
            rospy.sleep(MAPPING_STAND_S)
        code, out = save_map(env, out_dir, "lab")
        report["save"] = {"exit": code, "output": out.strip()[-500:]}
        if code != 0:
            raise RuntimeError("save_map failed: %s\n%s" % (out, env.tails()))
        stop_process(stack, timeout=20.0)
        report["mapping_run_s"] = time.monotonic() - t
        map_file = os.path.join(out_dir, "lab.yaml")
        report["saved_vs_world"] = saved_vs_world(map_file, world, first_start)
        if crowd_seconds > 0:  # the saved map is in the map frame: the crowd relative to home
            report["crowd"]["cells"] = crowd_cells(map_file, list(CROWD))
        t = time.monotonic()
        # --- 2a. placed where it cannot localize: never localized, preflight and the controller refuse --
        if far_check:
            for key, far_place in FAR_PLACES:
                report[key] = never_localized_run(env, rospy, world, seed, columns, first_start, map_file, far_place,
                                                  key + "_run")
        # --- 2. localization run, placed away from home -------------------------------------------------
        placed = compose(first_start, place)
        report["placed_world"] = [placed[0], placed[1], math.degrees(placed[2])]
        runner = sim_loops.Runner(map_origin=first_start, steer="corrected")
        watch = Watch(runner)
        stack = launch(env, "localization_run", world, seed, columns, placed, map_file)
        if not runner.wait_ready(120.0):
            raise RuntimeError("localization run: no ground truth / pose / odometry\n" + env.tails())
        wait_for(lambda: watch.first_sensor is not None, 30.0, "/ouster/imu")
        wait_for(lambda: any(v for _, v in watch.localized), 60.0, "/rbd_localization/localized true")
        report["preflight_localized"] = preflight_localized_row(env)
        end = watch.first_sensor + STAND_S
        while rospy.get_time() < end:
            rospy.sleep(0.2)
        with watch.lock:
            samples = list(watch.samples)
            localized = list(watch.localized)
            # the first sensor data this process saw, or the first pose if that came earlier (the
            # subscription to /ouster/imu may connect after the node's first scans)
            t0 = min([watch.first_sensor] + [sm[0] for sm in samples[:1]])
        watch.close()
        first_pose = samples[0] if samples else None
        report["convergence"] = {
            "t0_stamp": t0,
            "first_pose_after_s": None if first_pose is None else first_pose[0] - t0,
            "first_error": None if first_pose is None else [first_pose[1], first_pose[2]],
            "converged_after_s": converge_time(samples, t0),
            "localized_values": [v for _, v in localized],
            "localized_true_after_s": next((tt - t0 for tt, v in localized if v), None),
            "final_error": None if not samples else [samples[-1][1], samples[-1][2]],
            "samples": len(samples),
        }
        rospy.loginfo("convergence: %s", json.dumps(report["convergence"]))
        # --- 3. loops on the loaded map, steered on the localization --------------------------------------
        runner.go_to(0.0, 0.0)
        runner.turn_to(0.0)
        runner.settle_at(0.0, 0.0)
        rospy.sleep(1.0)
        report["home_reached"] = runner.errors()
        loops_report = sim_loops.drive_loops(runner, loops, settle=True)
        report["loops"] = loops_report["loops"]
        with runner.lock:
            xs = [p[0] for p in runner.tracks["truth"]]
        report["truth_x_range"] = [min(xs), max(xs)] if xs else None
        # --- 4. a box left on the floor, the map saved again -------------------------------------------
        if box_seconds > 0:
            from rbd_msgs.srv import PlaceBox

            place_box = rospy.ServiceProxy("/rbd_sim/place_box", PlaceBox)
            rospy.wait_for_service("/rbd_sim/place_box", 10.0)
            bx, by, _ = compose(first_start, (1.2, 0.0, 0.0))  # 1.2 m ahead of home (map +x), world
            res = place_box(name="left_box", x=bx, y=by, yaw=0.3, size_x=0.4, size_y=0.3, height=0.35, remove=False)
            report["box"] = {"placed": bool(res.success), "world_xy": [bx, by], "seconds": box_seconds}
            rospy.sleep(box_seconds)
            code, out = save_map(env, out_dir, "after_box")
            report["box"]["save_exit"] = code
            if code == 0:
                report["box"]["compare"] = compare_maps(map_file, os.path.join(out_dir, "after_box.yaml"))
        stop_process(stack, timeout=20.0)
        report["localization_run_s"] = time.monotonic() - t
    finally:
        env.close()
    with open(os.path.join(out_dir, "report.json"), "w") as f:
        json.dump(report, f, indent=1)
    return report


def main():
    """Command line: run the experiment, write OUT/report.json, print the summary."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True, help="directory for the maps, logs and report.json")
    ap.add_argument("--loops", type=int, default=10)
    ap.add_argument("--world", default="lab")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--columns", type=int, default=512)
    ap.add_argument("--box-seconds", type=float, default=0.0, help="leave a box in front this long, then save again")
    ap.add_argument("--crowd-seconds", type=float, default=0.0,
                    help="a crowd stands around the robot this long from the start of the mapping run")
    ap.add_argument("--far-check", action="store_true",
                    help="first restarts placed where it cannot localize (FAR_PLACES): localized must stay false")
    args = ap.parse_args()
    report = run(args.out, loops=args.loops, world=args.world, seed=args.seed, columns=args.columns,
                 box_seconds=args.box_seconds, crowd_seconds=args.crowd_seconds, far_check=args.far_check)
    summary = {k: report.get(k) for k in ("convergence", "preflight_localized", "home_reached", "box", "crowd")
               + tuple(key for key, _ in FAR_PLACES)}
    summary["loops"] = [{"loop": e["loop"], "truth_closure": e["truth_closure"], "corrected": e["corrected"]}
                        for e in report.get("loops", [])]
    print(json.dumps(summary, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
