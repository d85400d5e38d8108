"""rbd_preflight (ROS-free): each check against observations built here.

The facts of the real drivers come from ../shared/INTERFACES.md, written in this file as literal
tables (the ouster-ros point of point_type original, the A1 SDK packet sizes), never taken from
the module under test, rbd_lidar or rbd_a1_driver.
"""

import math

import numpy as np
import pytest

import rbd_preflight as pf

#: INTERFACES.md §1, ouster-ros point_type original: name, PointField datatype, offset.
OUSTER_ORIGINAL = [("x", 7, 0), ("y", 7, 4), ("z", 7, 8), ("intensity", 7, 16), ("t", 6, 20),
                   ("reflectivity", 4, 24), ("ring", 4, 26), ("ambient", 4, 28), ("range", 6, 32)]
POINT_STEP = 48
#: INTERFACES.md §2: HighState sizes on LCM_High_State.
SDK_V33, SDK_334, SDK_V32, SDK_V332 = 265, 1025, 256, 319


def cloud(rows=32, cols=1024, fields=None, point_step=POINT_STEP, frame="os_sensor", bigendian=False):
    fields = OUSTER_ORIGINAL if fields is None else fields
    return {"fields": [(n, o, d, 1) for n, d, o in fields], "point_step": point_step,
            "row_step": point_step * cols, "height": rows, "width": cols, "is_bigendian": bigendian,
            "data_len": point_step * cols * rows, "frame_id": frame}


def stream(rate, n=None, now=10.0, lag=0.02, duration=3.0):
    n = int(rate * duration) if n is None else n
    recv = [now - duration + (i + 0.5) / rate for i in range(n)]
    return pf.Stream(recv, [r - lag for r in recv])


def diag(**values):
    base = {"sdk_layout": "3.3.4", "sdk_layout_source": "auto", "high_state_size": "1025",
            "high_state_rate": "250.0", "high_cmd_rate": "250.0", "unknown_size_packets": "0",
            "estop_gate_armed": "true", "lcm_url": "udpm://239.255.76.67:7667?ttl=0"}
    base.update({k: str(v) for k, v in values.items()})
    return {"level": 0, "message": "ok", "values": base}


IDENTITY = (0.0, 0.0, 0.0, 1.0)


def healthy():
    """What a ready robot looks like: every check passes."""
    o = pf.Observation()
    o.duration, o.now = 3.0, 10.0
    o.streams = {"points": stream(10), "imu": stream(100), "zed2": stream(15), "zone": stream(10),
                 "pose": stream(30), "estop": stream(10, lag=0)}
    o.cloud = cloud()
    o.lidar_mode = "1024x10"
    o.zone_last = {"stale": False, "error": "", "collision": False, "points": [0, 0, 0, 0]}
    o.zed2_covariance = list(np.diag([1e-4] * 3 + [1e-5] * 3).ravel())
    o.a1_diag = [diag(), diag()]
    o.frames = {"os_sensor": ((-0.08, 0.0, 0.07), IDENTITY), "zed2_camera_center": ((0.22, 0.0, 0.06), IDENTITY),
                "collision_zone": ((-0.08, 0.0, 0.07), IDENTITY)}
    for name, (x, y) in {"FR_foot": (0.18, -0.13), "FL_foot": (0.18, 0.13), "RR_foot": (-0.18, -0.13),
                         "RL_foot": (-0.18, 0.13)}.items():
        o.frames[name] = ((x, y, -0.26), IDENTITY)  # foot sphere r 0.02 on a floor 0.28 m below
    o.cloud_xyz = floor_points(sensor_height=0.35)
    o.tf_edges = [("base_link", "os_sensor", "/robot_state_publisher", True),
                  ("base_link", "zed2_camera_center", "/robot_state_publisher", True),
                  ("odom", "base_link", "/ekf_localization", False)]
    o.bridge = {"node": "/rbd_bridge", "host": "10.0.0.2", "port": 9090, "listening": True, "error": None,
                "clients": ["192.168.12.20:51000"], "client_count": 1}
    o.clocks = {"10.0.0.2": (0.0, 0.0, "only host")}
    o.map_mode, o.localized = "mapping", True  # mapping mode after its initial mapping
    return o


def floor_points(sensor_height, n=3000, seed=0):
    """A level floor sensor_height below the sensor, 0.6-4 m around it, in the sensor frame."""
    rng = np.random.RandomState(seed)
    r = rng.uniform(0.6, 4.0, n)
    a = rng.uniform(-math.pi, math.pi, n)
    return np.stack([r * np.cos(a), r * np.sin(a), -sensor_height + rng.normal(0, 0.01, n)], axis=1)


def rows_of(o, **limits):
    return {r.key: r for r in pf.evaluate(o, pf.Limits(**limits))}


def failing(rows):
    return sorted(k for k, r in rows.items() if r.status == pf.FAIL)


def test_module_tables_equal_the_published_facts():
    assert {n: (o, d) for n, d, o in OUSTER_ORIGINAL} == {n: (o, t[0]) for n, (o, t) in pf.OUSTER_POINT.items()}
    assert pf.OUSTER_POINT_STEP == POINT_STEP
    assert set(pf.A1_STATE_SIZES) == {SDK_V33, SDK_334}
    assert pf.A1_HIGH_CMD_SIZE == 113


def test_a_ready_robot_passes_every_line():
    rows = pf.evaluate(healthy())
    assert [r.status for r in rows] == [pf.PASS] * len(pf.CHECKS), pf.render(rows)
    assert pf.passed(rows)
    text = pf.render(rows, healthy())
    assert "READY" in text and "os_sensor" in text and "xyz (-0.080, 0.000, 0.070) m" in text
    assert len([line for line in text.splitlines() if line.startswith("PASS")]) == len(pf.CHECKS)


@pytest.mark.parametrize("fault, key, text, skipped", [
    ("lidar silent", "lidar_cloud", "nothing in", {"lidar_layout", "zone", "floor"}),
    ("lidar slow", "lidar_cloud", "need >= 8 Hz", {"zone"}),
    ("lidar sensor time", "lidar_cloud", "s old on arrival", {"zone"}),
    ("zed2 silent", "zed2", "nothing in", set()),
    ("zed2 nan covariance", "zed2", "NaN", set()),
    ("imu slow", "lidar_imu", "need >= 80 Hz", set()),
    ("pose stale", "pose", "stale after", set()),
    ("estop silent", "estop", "nothing received", set()),
    ("gate not armed", "estop", "NOT armed", set()),
    ("no highstate", "a1_state", "0 Hz at the driver", set()),
    ("tf missing", "tf_lidar", "os_sensor missing", {"zone", "floor"}),
    ("zed2 frame missing", "tf_zed2", "zed2_camera_center missing", set()),
    ("two parents", "tf_parents", "zed2_camera_center has 2 parents", set()),
    ("two publishers", "tf_parents", "published by 2 nodes", set()),
    ("zone stale", "zone", "stale", set()),
    ("bridge down", "bridge", "not answering", set()),
    ("bridge missing", "bridge", "not running", set()),
    ("not localized", "localized", "not localized in the map (localization (/maps/lab.yaml))", set()),
])
def test_each_fault_fails_exactly_its_line(fault, key, text, skipped):
    o = healthy()
    if fault == "lidar silent":
        o.streams["points"] = pf.Stream()
        o.cloud = o.cloud_xyz = None
    elif fault == "lidar slow":
        o.streams["points"] = stream(5)
    elif fault == "lidar sensor time":
        o.streams["points"] = stream(10, lag=1.7e9)  # TIME_FROM_INTERNAL_OSC: seconds since the sensor booted
    elif fault == "zed2 silent":
        o.streams["zed2"] = pf.Stream()
    elif fault == "zed2 nan covariance":
        o.zed2_covariance[0] = float("nan")
    elif fault == "imu slow":
        o.streams["imu"] = stream(50)
    elif fault == "pose stale":
        o.streams["pose"] = stream(30, now=9.0)
    elif fault == "estop silent":
        o.streams["estop"] = pf.Stream()
    elif fault == "gate not armed":
        o.a1_diag = [diag(estop_gate_armed="false")]
    elif fault == "no highstate":
        o.a1_diag = [diag(high_state_rate=0, sdk_layout="3.3.4"), diag(high_state_rate=0, sdk_layout="3.3.4")]
    elif fault == "tf missing":
        o.frames["os_sensor"] = '"base_link" passed to lookupTransform argument target_frame does not exist'
    elif fault == "zed2 frame missing":
        o.frames["zed2_camera_center"] = "no such frame"
    elif fault == "two parents":
        o.tf_edges.append(("zed2_base_link", "zed2_camera_center", "/zed2/zed_state_publisher", True))
    elif fault == "two publishers":
        o.tf_edges.append(("odom", "base_link", "/zed2/zed_node", False))
    elif fault == "zone stale":
        o.zone_last["stale"] = True
    elif fault == "bridge down":
        o.bridge.update(listening=False, error="Connection refused")
    elif fault == "bridge missing":
        o.bridge = {"node": None}
    elif fault == "not localized":
        o.map_mode, o.localized = "localization (/maps/lab.yaml)", False
    rows = rows_of(o)
    assert failing(rows) == [key], pf.render(list(rows.values()))
    assert text in rows[key].value
    assert rows[key].hint
    assert {k for k, r in rows.items() if r.status == pf.SKIP} == skipped
    assert not pf.passed(list(rows.values()))


@pytest.mark.parametrize("mode, localized, status, text", [
    # a loaded map: FAIL until the start search converged, then PASS
    ("localization (/maps/lab.yaml)", False, pf.FAIL, "not localized in the map (localization (/maps/lab.yaml))"),
    ("localization (/maps/lab.yaml)", True, pf.PASS, "localized in the map (localization (/maps/lab.yaml))"),
    ("localization (/maps/lab.yaml)", None, pf.FAIL,
     "no /rbd_localization/localized in 3.0 s (map correction in localization (/maps/lab.yaml) mode)"),
    # no map: n/a, also while the initial mapping runs (the node says false then)
    ("mapping", True, pf.PASS, "n/a: no map loaded (map correction in mapping mode)"),
    ("mapping", False, pf.PASS, "n/a: no map loaded (map correction in mapping mode; initial mapping still running)"),
    (None, None, pf.PASS, "n/a: no map loaded (no /rbd_localization/localized"),
    # the mode not seen (diagnostics missed): the latched flag alone decides
    (None, False, pf.FAIL, "not localized in the map"),
    (None, True, pf.PASS, "localized in the map"),
])
def test_localized_line_fails_only_in_a_loaded_map_until_localized(mode, localized, status, text):
    o = healthy()
    o.map_mode, o.localized = mode, localized
    rows = rows_of(o)
    row = rows["localized"]
    assert row.status == status, row
    assert row.value.startswith(text), row.value
    assert failing(rows) == (["localized"] if status == pf.FAIL else [])
    assert bool(row.hint) == (status == pf.FAIL)
    if localized is False and status == pf.FAIL:
        assert "1 m / 45 deg" in row.hint  # what to do: where to place the robot


def test_collector_reads_the_localized_flag_and_the_map_correction_mode():
    """The adapter's callbacks with the real message types (no ROS master needed)."""
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    from std_msgs.msg import Bool

    from rbd_preflight import collect

    c = collect.Collector(duration=0.1, tap_lcm=False, measure_clocks=False)
    assert c.obs.localized is None and c.obs.map_mode is None
    other = DiagnosticStatus(name="ekf_localization: Filter", values=[KeyValue("mode", "something else")])
    ours = DiagnosticStatus(name="map_correction: Map correction",
                            values=[KeyValue("mapping", "False"), KeyValue("mode", "localization (/maps/lab.yaml)")])
    c._on_diag(DiagnosticArray(status=[other]))
    assert c.obs.map_mode is None
    c._on_diag(DiagnosticArray(status=[other, ours]))
    assert c.obs.map_mode == "localization (/maps/lab.yaml)"
    c._on_localized(Bool(data=False))
    assert rows_of(c.obs)["localized"].status == pf.FAIL
    c._on_localized(Bool(data=True))
    assert c.obs.localized is True


def test_cloud_layouts_other_than_ouster_original_fail_with_the_difference():
    cases = {
        "no field range": [f for f in OUSTER_ORIGINAL if f[0] != "range"],
        "range UINT16@32": [f if f[0] != "range" else ("range", 4, 32) for f in OUSTER_ORIGINAL],
        "intensity FLOAT32@12": [f if f[0] != "intensity" else ("intensity", 7, 12) for f in OUSTER_ORIGINAL],
    }
    for text, fields in cases.items():
        o = healthy()
        o.cloud = cloud(fields=fields)
        rows = rows_of(o)
        assert failing(rows) == ["lidar_layout"], text
        assert text in rows["lidar_layout"].value
    for change, text in ((dict(point_step=32), "point_step 32"), (dict(rows=16), "16 rows"),
                         (dict(cols=1000), "1000 columns"), (dict(bigendian=True), "big-endian"),
                         (dict(frame="os_lidar"), "frame 'os_lidar'")):
        o = healthy()
        o.cloud = cloud(**change)
        rows = rows_of(o)
        assert failing(rows) == ["lidar_layout"] and text in rows["lidar_layout"].value, change
    # ouster-ros before v0.7.1 (Dec 2022): ring UINT8 at the same offset is still the original layout
    o = healthy()
    o.cloud = cloud(fields=[f if f[0] != "ring" else ("ring", 2, 26) for f in OUSTER_ORIGINAL])
    assert rows_of(o)["lidar_layout"].status == pf.PASS


def test_highstate_sizes_name_the_sdk_or_say_unknown():
    o = healthy()
    o.wire = {"state_sizes": {SDK_334: 740, 300: 290}, "cmd_sizes": {113: 750}, "span": 3.0, "url": "udpm://x"}
    rows = rows_of(o)
    assert failing(rows) == ["a1_layout"]
    assert "300 B (unknown) x290" in rows["a1_layout"].value
    assert "265 B" in rows["a1_layout"].hint and "1025 B" in rows["a1_layout"].hint
    # a v3.2 robot: nothing usable (a1_state fails too), and the size is named
    o = healthy()
    o.a1_diag = [diag(high_state_rate=0, sdk_layout="unknown", high_state_size=SDK_V32, unknown_size_packets=10),
                 diag(high_state_rate=0, sdk_layout="unknown", high_state_size=SDK_V32, unknown_size_packets=510)]
    rows = rows_of(o)
    assert failing(rows) == ["a1_layout", "a1_state"]
    assert "500 dropped by the driver, last size 256 B (SDK v3.2, not supported)" in rows["a1_layout"].value
    # without a tap, the driver's counter alone
    o = healthy()
    o.a1_diag = [diag(unknown_size_packets=3), diag(unknown_size_packets=40)]
    assert failing(rows_of(o)) == ["a1_layout"]
    # both known layouts pass
    for layout, size in (("3.3", SDK_V33), ("3.3.4", SDK_334)):
        o = healthy()
        o.a1_diag = [diag(sdk_layout=layout, high_state_size=size)]
        o.wire = {"state_sizes": {size: 750}, "cmd_sizes": {113: 750}, "span": 3.0, "url": "udpm://x"}
        row = rows_of(o)["a1_layout"]
        assert row.status == pf.PASS and "HighState %d B" % size in row.value


def test_a_second_highcmd_sender_on_the_wire_fails_the_highcmd_line():
    o = healthy()
    o.wire = {"state_sizes": {SDK_334: 750}, "cmd_sizes": {113: 750, 143: 20}, "span": 3.0, "url": "udpm://x"}
    rows = rows_of(o)
    assert failing(rows) == ["a1_cmd"] and "143 B x20" in rows["a1_cmd"].value


def test_covariance_sanity():
    lim = pf.Limits()
    good = np.diag([1e-4] * 3 + [1e-5] * 3)
    assert pf.covariance_problem(good.ravel(), lim) is None
    asym = good.copy()
    asym[0, 1] = 1e-3
    assert "not symmetric" in pf.covariance_problem(asym.ravel(), lim)
    assert "all zero" in pf.covariance_problem(np.zeros(36), lim)
    neg = good.copy()
    neg[2, 2] = -1e-4
    assert "negative" in pf.covariance_problem(neg.ravel(), lim)
    huge = good.copy()
    huge[0, 0] = 4.0
    assert "too large" in pf.covariance_problem(huge.ravel(), lim)
    assert "30 numbers" in pf.covariance_problem(np.zeros(30), lim)


def test_floor_offset_equals_the_mount_error_and_its_sign():
    # The sensor really is 0.35 m above the floor; the mounts file says 0.07 m above base_link
    # (0.28 m): passes. Told 0.10 m higher than it is: the floor shows 0.10 m high.
    o = healthy()
    assert rows_of(o)["floor"].status == pf.PASS
    for error in (0.10, -0.06):
        o = healthy()
        o.frames["os_sensor"] = ((-0.08, 0.0, 0.07 + error), IDENTITY)
        rows = rows_of(o)
        assert failing(rows) == ["floor"], error
        offset = float(rows["floor"].value.split()[1])
        assert offset == pytest.approx(error, abs=0.005)
        assert ("too high" if error > 0 else "too low") in rows["floor"].hint
    # within the tolerance: passes
    o = healthy()
    o.frames["os_sensor"] = ((-0.08, 0.0, 0.09), IDENTITY)
    assert rows_of(o)["floor"].status == pf.PASS


def test_floor_follows_the_feet_and_a_tilted_mount_fails():
    # Body lowered 0.1 m (lie down): the feet say so, the LiDAR sees the floor 0.1 m closer.
    o = healthy()
    for f in pf.FEET:
        (x, y, z), q = o.frames[f]
        o.frames[f] = ((x, y, z + 0.1), q)
    o.cloud_xyz = floor_points(sensor_height=0.25)
    assert rows_of(o)["floor"].status == pf.PASS
    # Without foot frames: the nominal standing height.
    o = healthy()
    for f in pf.FEET:
        del o.frames[f]
    row = rows_of(o)["floor"]
    assert row.status == pf.PASS and "nominal 0.28 m" in row.value
    # The OS1 pitched 5 deg on its mount while the file says level: a tilted floor.
    o = healthy()
    a = math.radians(5.0)
    rot = np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])
    o.cloud_xyz = floor_points(0.35).dot(rot)  # points seen by the pitched sensor
    rows = rows_of(o)
    assert failing(rows) == ["floor"] and "tilted" in rows["floor"].hint
    # No floor in sight (e.g. a cover on the sensor).
    o = healthy()
    o.cloud_xyz = np.zeros((0, 3))
    assert "no floor" in rows_of(o)["floor"].value


def test_fit_plane_finds_the_dominant_plane_among_outliers():
    rng = np.random.RandomState(3)
    floor = np.stack([rng.uniform(-3, 3, 2000), rng.uniform(-3, 3, 2000), -0.3 + rng.normal(0, 0.01, 2000)], 1)
    clutter = rng.uniform(-3, 3, (500, 3))
    n, d, inliers = pf.fit_plane(np.vstack([floor, clutter]))
    assert n[2] == pytest.approx(1.0, abs=1e-3) and d == pytest.approx(0.3, abs=0.003)
    assert inliers >= 1900
    assert pf.fit_plane(np.zeros((2, 3))) is None


def test_clocks_need_every_pair_within_50_ms_counting_the_uncertainty():
    o = healthy()
    o.clocks = {"a": (0.0, 0.001, "u"), "b": (0.030, 0.002, "u")}
    assert rows_of(o)["clocks"].status == pf.PASS
    o.clocks = {"a": (0.0, 0.001, "u"), "b": (0.030, 0.002, "u"), "c": (-0.025, 0.002, "u")}
    rows = rows_of(o)
    assert failing(rows) == ["clocks"] and "b vs c up to 59 ms" in rows["clocks"].value
    o.clocks = {"a": (0.0, 0.001, "u"), "b": (0.040, 0.015, "u")}  # cannot be sure: 40 ms +- 16
    assert rows_of(o)["clocks"].status == pf.FAIL
    o.clocks = {"a": (0.0, 0.001, "u"), "laptop": "no Date header from 1 server(s)"}
    rows = rows_of(o)
    assert failing(rows) == ["clocks"] and "laptop" in rows["clocks"].value
    o.clocks = None
    assert rows_of(o)["clocks"].status == pf.SKIP


def test_bridge_names_its_clients():
    o = healthy()
    assert "1 client(s): 192.168.12.20:51000" in rows_of(o)["bridge"].value
    o.bridge.update(clients=[], client_count=0)
    assert "no clients connected" in rows_of(o)["bridge"].value


def test_a_bug_in_one_check_fails_only_its_line(monkeypatch):
    def broken(_o, _l):
        raise RuntimeError("boom")
    checks = [(k, n, broken if k == "imu" or k == "lidar_imu" else f, needs) for k, n, f, needs in pf.CHECKS]
    monkeypatch.setattr(pf.table, "CHECKS", checks)  # evaluate() reads the table of its own module
    rows = rows_of(healthy())
    assert failing(rows) == ["lidar_imu"] and "boom" in rows["lidar_imu"].value


def test_limits_reject_unknown_names():
    with pytest.raises(ValueError, match="floor_tolerence"):
        pf.Limits(floor_tolerence=0.1)
    assert pf.Limits(clock_max_skew=0.01).clock_max_skew == 0.01
