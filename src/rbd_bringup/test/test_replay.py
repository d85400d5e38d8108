"""Record the simulated robot's inputs, replay them through robot.launch, and preflight passes.

The recording is made the way ``make demo`` makes its own (``rosrun rbd_bringup record``) from
rbd_sim's hardware stand-ins (mock A1 on its own LCM URL, simulated OS1 and ZED2, SDK 3.3.4),
then ``roslaunch rbd_bringup robot.launch replay:=DIR`` runs the robot stack on it with its own
master. Ground truth for "no HighCmd to a live LCM URL": an LCM listener on the Unitree SDK's URL
(udpm://239.255.76.67:7667?ttl=0) hears none, while one on the replay's URL hears the driver's
HighCmd stream (so the driver did send). Start it under ``flock /tmp/rbd-sim.lock``.
"""

import json
import os
import subprocess
import threading

import lcm
import rosgraph

from rbd_bringup import recording
from rbd_testkit import RosEnv, free_port, wait_for

SDK_URL = "udpm://239.255.76.67:7667?ttl=0"
HIGH_CMD_SIZE = 113  # INTERFACES.md §2: HighCmd of every A1 SDK release


class LcmCount:
    """Counts the packets per size on one channel of an LCM URL, in a thread."""

    def __init__(self, url, channel="LCM_High_Cmd"):
        self.sizes = {}
        self.lc = lcm.LCM(url)
        self.lc.subscribe(channel, lambda _c, data: self.sizes.__setitem__(len(data), self.sizes.get(len(data), 0) + 1))
        self.running = True
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def run(self):
        while self.running:
            self.lc.handle_timeout(50)

    def close(self):
        self.running = False
        self.thread.join(2.0)


def param(name):
    try:
        return rosgraph.Master("/test_replay").getParam(name)
    except (rosgraph.MasterError, OSError):
        return None


def publishes(topic):
    try:
        return any(t == topic and nodes for t, nodes in rosgraph.Master("/test_replay").getSystemState()[0])
    except OSError:
        return False


def preflight(env, duration=3.0):
    out = subprocess.run(["rosrun", "rbd_preflight", "preflight", "--json", "--duration", str(duration)],  # noqa: UP022
                         env=env.env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True,
                         timeout=90)
    report = json.loads(out.stdout)
    table = "\n".join("%(status)s %(name)s: %(value)s %(hint)s" % r for r in report["rows"])
    return out.returncode, report, table


def test_preflight_passes_on_a_replay_that_sends_no_highcmd_to_the_sdk_url(tmp_path):
    rec = str(tmp_path / "recording")
    # 1. the recording, from the hardware stand-ins alone
    with RosEnv(use_here=True, prefix="rbd-replay-rec.") as env:
        env.launch("rbd_sim", "sim.launch", "lidar_columns:=512", "publish_mount_tf:=false", name="sim")
        wait_for(lambda: publishes("/ouster/points") and publishes("/zed2/zed_node/pose_with_covariance")
                 and param("/rbd_sim/lcm_url"), 120.0, 0.2, what="the simulated hardware up")
        code, out = env.run_to_exit(["rosrun", "rbd_bringup", "record", rec, "--duration", "10"], timeout=120.0)
        assert code == 0, out
    sizes = {n: os.path.getsize(os.path.join(rec, n)) for n in os.listdir(rec)}
    assert recording.recording_problems(sizes) == [], sizes
    print("recording: %s" % sizes)

    # 2. the robot stack on it
    live = LcmCount(SDK_URL)
    env = RosEnv(use_here=True, prefix="rbd-replay-run.")
    private = None
    try:
        env.launch("rbd_bringup", "robot.launch", "replay:=%s" % rec, "bridge_port:=%d" % free_port(),
                   "bridge_address:=127.0.0.1", name="robot")
        wait_for(lambda: param("/replay/started"), 150.0, 0.2, what="the replay playing")
        url = param("/rbd_a1_driver/lcm_url")
        assert recording.private_lcm_url_problem(url) is None, url
        private = LcmCount(url)
        code, report, table = preflight(env)
        if code != 0:  # the stack may still have been warming up on a loaded machine: once more
            print("first preflight on the replay:\n" + table)
            code, report, table = preflight(env, 2.5)
        assert code == 0 and report["ready"], table
        print("preflight on the replay:\n" + table)
        rows = {r["key"]: r for r in report["rows"]}
        assert "SDK 3.3.4" in rows["a1_layout"]["value"], table
        # the driver did send, on the replay's private URL only
        assert wait_for(lambda: private.sizes.get(HIGH_CMD_SIZE, 0) > 100, 10.0), private.sizes
        assert live.sizes == {}, live.sizes
    finally:
        live.close()
        if private is not None:
            private.close()
        env.close(timeout=20.0)
