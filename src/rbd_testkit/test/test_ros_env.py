"""RosEnv against a real rosmaster: private environment, logs, run to exit, and a clean stop."""

import os
import socket
import sys
import textwrap

import rosgraph

from rbd_testkit import RosEnv, wait_for

# A "node" that roslaunch would leave behind: a session of its own, ignoring SIGINT.
ORPHAN = textwrap.dedent("""
    import os, signal, subprocess, sys
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    subprocess.Popen([sys.executable, "-c", "import signal, time; signal.signal(signal.SIGINT, signal.SIG_IGN); "
                      "print('orphan', flush=True); time.sleep(120)"], start_new_session=True)
""")


def test_private_master_processes_and_close(tmp_path):
    before = dict(os.environ)
    env = RosEnv(log_dir=str(tmp_path))
    try:
        assert env.uri == "http://127.0.0.1:%d" % env.port
        assert env.env["ROS_MASTER_URI"] == env.uri and env.env["ROS_HOME"] == env.home
        assert os.environ.get("ROS_MASTER_URI") == before.get("ROS_MASTER_URI")  # not used here unless asked
        assert rosgraph.Master("/rbd_testkit_test", master_uri=env.uri).getPid() == env.master.pid

        code, out = env.run_to_exit([sys.executable, "-c", "import os; print(os.environ['ROS_MASTER_URI']); exit(4)"])
        assert (code, out.strip()) == (4, env.uri)

        env.start([sys.executable, "-c", ORPHAN], name="launcher")
        assert wait_for(lambda: _orphans(env), 20.0), "the orphan started"
        captured = env.start([sys.executable, "-c", "print('to the pipe')"], capture=True)
        assert captured.stdout.readline().strip() == "to the pipe"
        env.use_in_this_process()
        assert os.environ["ROS_MASTER_URI"] == env.uri
    finally:
        orphans = _orphans(env)
        env.close()
        for key in ("ROS_MASTER_URI", "ROS_HOME", "ROS_LOG_DIR", "ROS_IP"):
            if key in before:
                os.environ[key] = before[key]
            else:
                os.environ.pop(key, None)
    assert not os.path.exists(env.home)
    assert all(not os.path.exists("/proc/%d" % pid) or _zombie(pid) for pid in orphans)
    assert os.path.exists(str(tmp_path / "rosmaster.log")) and os.path.exists(str(tmp_path / "launcher.log"))
    with socket.socket() as s:
        assert s.connect_ex(("127.0.0.1", env.port)) != 0  # the master is gone


def _orphans(env):
    from rbd_testkit.process import pids_with_env

    return [pid for pid in pids_with_env("ROS_HOME", env.home) if pid not in [p.pid for p in env.procs]]


def _zombie(pid):
    try:
        with open("/proc/%d/stat" % pid) as f:
            return f.read().rsplit(")", 1)[1].split()[0] == "Z"
    except OSError:
        return True


LATCHED = textwrap.dedent("""
    import rospy
    from std_msgs.msg import String
    from rbd_testkit import wait_for
    from rbd_testkit.ros import messages_received, subscriber_nodes

    rospy.init_node("latch_probe")
    pub = rospy.Publisher("/latched", String, queue_size=1, latch=True)
    pub.publish(String("x"))
    print("before", subscriber_nodes(pub), flush=True)
    got = []
    rospy.Subscriber("/latched", String, got.append)
    wait_for(lambda: "/latch_probe" in subscriber_nodes(pub), 20.0, what="the probe's own connection")
    wait_for(lambda: got, 5.0, what="the latched message")
    print("after", subscriber_nodes(pub), [m.data for m in got], flush=True)
    pub.publish(String("y"))
    wait_for(lambda: len(got) == 2, 5.0, what="the second message")
    print("received", messages_received("/latch_probe", "/latched"), messages_received("/latch_probe", "/other"),
          flush=True)
""")


def test_subscriber_nodes_and_messages_received_see_a_nodes_own_topic(tmp_path):
    with RosEnv(log_dir=str(tmp_path)) as env:
        code, out = env.run_to_exit([sys.executable, "-c", LATCHED])
    assert code == 0, out
    assert "before []" in out and "after ['/latch_probe'] ['x']" in out and "received 2 0" in out, out
