"""A client leaves as a ROS subscriber connects; the next client's messages must still reach it.

The "known gap" of issue 18: the bridge unregistered a topic's rospy publisher the moment
its last client left. A rospy subscriber whose TCP connection reached the bridge in that
moment was refused, and rospy (checking once, a second later, that the bridge still
publishes the topic) gave the connection up but kept it on its books: it never connected
to the next client's advertise of the same topic. At a fair: the laptop reconnects just as
rbd_gestrec connects. With ``~publisher_linger`` (default) the publisher stays registered
for a while after the last client leaves and is reused by the next advertise.

The clients are roslibpy; the subscriber is plain rospy in its own process
(``ros_probe.py``), asked to subscribe to many topics in a row while client A leaves, so
that some of the connection attempts meet the moment A's publishers go.
"""

import time

import pytest
import roslibpy
from rbd_bridge_testing import master_of, probe_call, start_bridge, start_probe, wait_until

from rbd_testkit import RosEnv

PROBE = "linger_probe"
TOPICS = ["/linger/t%02d" % i for i in range(24)]
BRIDGE = "/rbd_bridge"
GAP = 2.5  # s between A leaving and B advertising: > rospy's 1 s re-check, < the default linger


@pytest.fixture(scope="module")
def bridge():
    """Master, a bridge with the default linger, a probe that subscribes on request."""
    env = RosEnv()
    try:
        port, _ = start_bridge(env, topics_glob="[/linger/*]")
        start_probe(env, PROBE, subs=["%s:std_msgs/String:0" % t for t in TOPICS], defer=0.0)
        yield env, port
    finally:
        env.close()


def _publishers(env, topics):
    state = dict((t, nodes) for t, nodes in master_of(env).getSystemState()[0])
    return [t for t in topics if BRIDGE in state.get(t, [])]


def _connect(port):
    ros = roslibpy.Ros("127.0.0.1", port, transport="asyncio")
    ros.run(timeout=15)
    return ros


def test_a_subscriber_connecting_as_the_last_client_leaves_gets_the_next_clients_messages(bridge):
    env, port = bridge
    a, b = _connect(port), _connect(port)
    try:
        for topic in TOPICS:
            roslibpy.Topic(a, topic, "std_msgs/String").advertise()
        assert wait_until(lambda: len(_publishers(env, TOPICS)) == len(TOPICS), 15)
        probe_call(env, PROBE, "subscribe")  # the probe subscribes to the topics one after another
        a.close()  # ... while A leaves: the bridge's publishers go as the connections come
        time.sleep(GAP)  # B (connected already) advertises the same topics a moment later
        pubs = [roslibpy.Topic(b, topic, "std_msgs/String") for topic in TOPICS]
        for pub in pubs:
            pub.advertise()
        left = {"topics": TOPICS}

        def all_arrived():
            for pub in pubs:
                pub.publish(roslibpy.Message({"data": "from B"}))
            report = probe_call(env, PROBE)
            left["topics"] = [t for t in TOPICS if "from B" not in str(report.get(t, {}).get("messages"))]
            return not left["topics"]

        assert wait_until(all_arrived, 15, step=0.2), "B's messages never reached ROS on %s" % left["topics"]
    finally:
        for ros in (a, b):
            ros.close()
