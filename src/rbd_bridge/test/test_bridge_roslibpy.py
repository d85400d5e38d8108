"""roslibpy (the real client library) against a real bridge, master and echo peer."""

import itertools
import json
import threading
import time

import pytest
import rosgraph
import roslibpy
from rbd_bridge_testing import LINGER, master_of, png_text, start_echo, wait_until

from rbd_bridge.core.rosapi import ROSAPI_TYPES
from rbd_testkit import free_port, stays_unchanged, wait_quiet

BRIDGE = "/rbd_bridge"


class Inbox:
    def __init__(self):
        self.items = []
        self.lock = threading.Lock()

    def __call__(self, msg):
        with self.lock:
            self.items.append(msg)

    def wait(self, predicate=lambda m: True, timeout=10.0):
        return wait_until(lambda: [m for m in list(self.items) if predicate(m)], timeout)

    def count(self):
        return len(self.items)


def protocol_of(ros):
    """roslibpy's protocol object of a connected Ros (on_ready fires at once when connected)."""
    got = []
    ros.factory.on_ready(got.append)
    assert got, "not connected"
    return got[0]


def listen(ros, op):
    """Collect every frame of one op on ros's connection (roslibpy has no handler for these)."""
    inbox = Inbox()
    proto = protocol_of(ros)
    if proto._message_handlers.get(op, False) is None:
        proto._message_handlers[op] = inbox  # "status" is pre-registered as None (roslibpy raises on it)
    else:
        proto.register_message_handlers(op, inbox)
    return inbox


def rosapi(ros, service, **args):
    """Call /rosapi/<service> through roslibpy."""
    return roslibpy.Service(ros, "/rosapi/" + service, ROSAPI_TYPES[service]).call(
        roslibpy.ServiceRequest(args), timeout=10
    )


def call_raw(ros, frame, timeout=10):
    """Send a hand-made call_service frame through roslibpy and wait for its service_response."""
    frame = dict(frame, op="call_service")
    frame.setdefault("id", "raw:%d" % ros.id_counter)
    return ros.call_sync_service(roslibpy.Message(frame), timeout)


def keep_publishing(topic, make_msg, until, timeout=10.0, period=0.1):
    """Publish until the predicate holds (subscriptions connect asynchronously in ROS)."""
    sent = [0]

    def publish_then_check():
        topic.publish(roslibpy.Message(make_msg(sent[0])))
        sent[0] += 1
        return until()

    return bool(wait_until(publish_then_check, timeout, period))


def test_advertise_publish_subscribe_round_trip_through_ros(roslibpy_client):
    ros = roslibpy_client()
    inbox = Inbox()
    out = roslibpy.Topic(ros, "/echo/out", "std_msgs/String")
    out.subscribe(inbox)
    pub = roslibpy.Topic(ros, "/echo/in", "std_msgs/String")
    pub.advertise()
    # (this test's own messages: an echo of an earlier test's publish may still come in first)
    assert keep_publishing(pub, lambda i: {"data": "hello %d" % i},
                           lambda: [m for m in inbox.items if m["data"].startswith("hello ")])
    pub.unadvertise()
    out.unsubscribe()


def test_publish_without_advertise_infers_the_type(roslibpy_client):
    ros = roslibpy_client()
    inbox = Inbox()
    roslibpy.Topic(ros, "/echo/out", "std_msgs/String").subscribe(inbox)
    def sent_and_echoed():
        ros.send_on_ready(roslibpy.Message({"op": "publish", "topic": "/echo/in", "msg": {"data": "no advertise"}}))
        return {"data": "no advertise"} in inbox.items

    wait_until(sent_and_echoed, 10, 0.1)
    assert {"data": "no advertise"} in inbox.items, inbox.items[:3]


def test_subscribe_without_type_and_latched_message_reaches_every_new_subscriber(roslibpy_client):
    first, second = Inbox(), Inbox()
    ros1 = roslibpy_client()
    roslibpy.Topic(ros1, "/echo/latched", None).subscribe(first)
    assert first.wait(timeout=10)[0] == {"data": "hello latched"}
    ros2 = roslibpy_client()  # the bridge already subscribes: served from its latched cache
    roslibpy.Topic(ros2, "/echo/latched", "std_msgs/String").subscribe(second)
    assert second.wait(timeout=10)[0] == {"data": "hello latched"}


def test_throttle_rate_limits_delivery(roslibpy_client):
    ros = roslibpy_client()
    fast, slow = Inbox(), Inbox()
    roslibpy.Topic(ros, "/echo/tick", "std_msgs/Header").subscribe(fast)
    ros2 = roslibpy_client()
    roslibpy.Topic(ros2, "/echo/tick", "std_msgs/Header", throttle_rate=250).subscribe(slow)
    assert fast.wait(timeout=10) and slow.wait(timeout=10)
    n_fast, n_slow = fast.count(), slow.count()
    time.sleep(2.0)
    got_fast, got_slow = fast.count() - n_fast, slow.count() - n_slow
    assert got_fast > 40  # 50 Hz peer
    assert 3 <= got_slow <= 10  # one per 250 ms
    stamps = [m["stamp"] for m in fast.items[-5:]]
    assert all(set(s) == {"secs", "nsecs"} and s["secs"] > 0 for s in stamps)


def test_int64_exact_nan_null_and_header_stamp_filled_through_ros(roslibpy_client):
    ros = roslibpy_client()
    ints, floats, poses = Inbox(), Inbox(), Inbox()
    roslibpy.Topic(ros, "/t/i64", "std_msgs/Int64").subscribe(ints)
    roslibpy.Topic(ros, "/t/f64", "std_msgs/Float64").subscribe(floats)
    roslibpy.Topic(ros, "/t/pose", "geometry_msgs/PoseStamped").subscribe(poses)
    pub_ros = roslibpy_client()
    i64 = roslibpy.Topic(pub_ros, "/t/i64", "std_msgs/Int64")
    f64 = roslibpy.Topic(pub_ros, "/t/f64", "std_msgs/Float64")
    pose = roslibpy.Topic(pub_ros, "/t/pose", "geometry_msgs/PoseStamped")
    assert keep_publishing(i64, lambda i: {"data": 2**63 - 1}, lambda: ints.items)
    assert ints.items[0]["data"] == 2**63 - 1
    assert keep_publishing(f64, lambda i: {"data": 7}, lambda: [m for m in floats.items if m["data"] == 7.0])
    f64.publish(roslibpy.Message({"data": None}))  # NaN in, NaN through ROS, null out
    assert wait_until(lambda: {"data": None} in floats.items, 5)
    assert keep_publishing(pose, lambda i: {"pose": {"position": {"x": 1.5}}}, lambda: poses.items)
    got = poses.items[0]
    assert got["header"]["stamp"]["secs"] > 1e9 and got["pose"]["position"]["x"] == 1.5
    assert got["pose"]["orientation"] == {"x": 0.0, "y": 0.0, "z": 0.0, "w": 0.0}


def test_call_service_success_failure_and_missing_service(roslibpy_client):
    ros = roslibpy_client()
    srv = roslibpy.Service(ros, "/echo/set_bool", "std_srvs/SetBool")
    assert srv.call(roslibpy.ServiceRequest({"data": True}), timeout=10) == {"success": True, "message": "echo"}
    assert srv.call(roslibpy.ServiceRequest({}), timeout=10) == {"success": False, "message": "echo"}
    with pytest.raises(roslibpy.core.ServiceException, match="always fails"):
        roslibpy.Service(ros, "/echo/fail", "std_srvs/Trigger").call(roslibpy.ServiceRequest(), timeout=10)
    with pytest.raises(roslibpy.core.ServiceException, match="does not exist"):
        roslibpy.Service(ros, "/no/such", "std_srvs/Trigger").call(roslibpy.ServiceRequest(), timeout=10)
    with pytest.raises(roslibpy.core.ServiceException, match="unknown field"):
        srv.call(roslibpy.ServiceRequest({"dta": True}), timeout=10)


def _service_gone(master, name):
    """True once the master answers that no node provides the service.

    Only that answer counts: any other failure (the master unreachable, a timeout) raises, so a
    wait on this never passes because the question could not be asked.
    """
    try:
        master.lookupService(name)
        return False
    except rosgraph.masterapi.Error as err:  # the master's ERROR code (-1)
        if "no provider" in str(err):
            return True
        raise


def test_service_gone_needs_the_masters_answer():
    # An unreachable master is no proof that a service is gone.
    master = rosgraph.Master("/rbd_bridge_test", master_uri="http://127.0.0.1:%d" % free_port())
    with pytest.raises(OSError):
        _service_gone(master, "/web/negate")


def test_client_hosted_service_is_a_ros_service_and_disappears_with_its_client(roslibpy_client, open_bridge):
    provider = roslibpy_client()
    seen = []

    def handler(request, response):
        seen.append(request)
        response["success"] = not request["data"]
        response["message"] = "from the web"
        return True

    service = roslibpy.Service(provider, "/web/negate", "std_srvs/SetBool")
    service.advertise(handler)
    master = master_of(open_bridge.env)
    assert wait_until(lambda: master.lookupService("/web/negate"), 10)
    caller = roslibpy_client()
    result = roslibpy.Service(caller, "/web/negate", "std_srvs/SetBool").call(
        roslibpy.ServiceRequest({"data": True}), timeout=10
    )
    assert result == {"success": False, "message": "from the web"} and seen == [{"data": True}]
    provider.close()

    assert wait_until(
        lambda: _service_gone(master, "/web/negate"), 10
    ), "the service must be unregistered when its client disconnects"


def test_ros_provider_vanishing_mid_call_gives_an_error_not_a_hang(roslibpy_client, open_bridge):
    victim = start_echo(open_bridge.env, ns="/victim")
    ros = roslibpy_client()
    errors = []
    done = threading.Event()

    def errback(err):
        errors.append(err)
        done.set()

    roslibpy.Service(ros, "/victim/echo/slow", "std_srvs/Trigger").call(
        roslibpy.ServiceRequest(), callback=lambda r: done.set(), errback=errback
    )
    time.sleep(1.0)
    start = time.monotonic()
    victim.kill()
    assert done.wait(15), "no reply after the provider died"
    assert errors and isinstance(errors[0], str)
    assert time.monotonic() - start < 15


def test_rosapi_calls_roslibpy_uses(roslibpy_client):
    ros = roslibpy_client()
    topics = ros.get_topics()
    assert "/echo/out" in topics and "/echo/tick" in topics
    assert ros.get_topic_type("/echo/tick") == "std_msgs/Header"
    assert "/echo/tick" in ros.get_topics_for_type("std_msgs/Header")
    services = ros.get_services()
    assert "/echo/set_bool" in services and "/rosapi/topics" in services
    assert ros.get_service_type("/echo/set_bool") == "std_srvs/SetBool"
    assert ros.get_service_type("/rosapi/get_time") == "rosapi/GetTime"
    assert "/echo/set_bool" in ros.get_services_for_type("std_srvs/SetBool")
    nodes = ros.get_nodes()
    assert "/echo_node" in nodes and "/rbd_bridge" in nodes
    details = ros.get_node_details("/echo_node")
    assert "/echo/in" in details["subscribing"] and "/echo/tick" in details["publishing"]
    assert "/echo/set_bool" in details["services"]
    typedefs = ros.get_message_details("geometry_msgs/PoseStamped")["typedefs"]
    assert typedefs[0]["type"] == "geometry_msgs/PoseStamped"
    request = ros.get_service_request_details("std_srvs/SetBool")["typedefs"][0]
    assert request["fieldnames"] == ["data"] and request["fieldtypes"] == ["bool"]
    response = ros.get_service_response_details("std_srvs/SetBool")["typedefs"][0]
    assert response["fieldnames"] == ["success", "message"]
    now = ros.get_time()
    assert abs(now["secs"] - time.time()) < 5
    ros.set_param("/rbd_test/value", {"a": [1, 2], "b": "x"})
    assert ros.get_param("/rbd_test/value") == {"a": [1, 2], "b": "x"}
    assert "/rbd_test/value/a" in ros.get_params() or "/rbd_test/value" in ros.get_params()
    has = roslibpy.Service(ros, "/rosapi/has_param", "rosapi/HasParam")
    assert has.call(roslibpy.ServiceRequest({"name": "/rbd_test/value"}), timeout=10) == {"exists": True}
    ros.delete_param("/rbd_test/value")
    assert has.call(roslibpy.ServiceRequest({"name": "/rbd_test/value"}), timeout=10) == {"exists": False}
    # no fixture advertises an action server; another test's leftovers may still be
    # registered, so the truth is the topic list: every prefix with all five topics
    names = ros.get_topics()
    suffixes = ("/goal", "/cancel", "/status", "/feedback", "/result")
    prefixes = {name.rsplit("/", 1)[0] for name in names}
    expected = sorted(p for p in prefixes if all(p + suffix in names for suffix in suffixes))
    servers = []
    ros.get_action_servers(servers.append)
    assert wait_until(lambda: servers, 10)
    assert sorted(servers[0]["action_servers"]) == expected
    pubs = roslibpy.Service(ros, "/rosapi/publishers", "rosapi/Publishers").call(
        roslibpy.ServiceRequest({"topic": "/echo/tick"}), timeout=10
    )
    assert pubs == {"publishers": ["/echo_node"]}


def graph_nodes(open_bridge, kind, topic):
    """Nodes the master lists as publishers (kind 0) or subscribers (kind 1) of topic."""
    for name, nodes in master_of(open_bridge.env).getSystemState()[kind]:
        if name == topic:
            return nodes
    return []


def test_unadvertise_unregisters_the_bridge_publisher_once_no_client_holds_it(roslibpy_client, open_bridge):
    topic = "/rbd_test/unadvertise"
    first, second = roslibpy_client(), roslibpy_client()
    pub1 = roslibpy.Topic(first, topic, "std_msgs/String")
    pub2 = roslibpy.Topic(second, topic, "std_msgs/String")
    pub1.advertise()
    pub2.advertise()
    assert wait_until(lambda: BRIDGE in rosapi(first, "publishers", topic=topic)["publishers"], 10)
    pub1.unadvertise()
    # the second client still advertises: the ROS publisher stays (checked after a reply that
    # the bridge sends after handling the unadvertise, on the same connection)
    assert BRIDGE in rosapi(first, "publishers", topic=topic)["publishers"]
    assert BRIDGE in graph_nodes(open_bridge, 0, topic)
    start = time.monotonic()
    pub2.unadvertise()
    assert wait_until(lambda: BRIDGE not in rosapi(second, "publishers", topic=topic)["publishers"], 10)
    assert time.monotonic() - start >= LINGER  # not at once: it lingered for the next advertiser
    assert BRIDGE not in graph_nodes(open_bridge, 0, topic)  # the master agrees


def test_unsubscribe_by_id_keeps_a_merged_subscription_until_the_last_id_goes(roslibpy_client, open_bridge):
    ros = roslibpy_client()
    a, b = Inbox(), Inbox()
    sub_a = roslibpy.Topic(ros, "/echo/out", "std_msgs/String")
    sub_b = roslibpy.Topic(ros, "/echo/out", "std_msgs/String", throttle_rate=0)
    sub_a.subscribe(a)
    sub_b.subscribe(b)
    pub = roslibpy.Topic(roslibpy_client(), "/echo/in", "std_msgs/String")
    assert keep_publishing(pub, lambda i: {"data": "both %d" % i}, lambda: a.items)
    assert BRIDGE in rosapi(ros, "subscribers", topic="/echo/out")["subscribers"]
    sub_a.unsubscribe()
    # roslibpy dropped its local callbacks for the topic on unsubscribe: listen again, and the
    # bridge must still deliver for the other id of this connection
    after = Inbox()
    ros.on("/echo/out", after)
    assert keep_publishing(
        pub, lambda i: {"data": "still %d" % i}, lambda: [m for m in after.items if "still" in m["data"]]
    )
    assert BRIDGE in rosapi(ros, "subscribers", topic="/echo/out")["subscribers"]
    sub_b.unsubscribe()
    assert wait_until(lambda: BRIDGE not in rosapi(ros, "subscribers", topic="/echo/out")["subscribers"], 10)
    assert BRIDGE not in graph_nodes(open_bridge, 1, "/echo/out")
    assert "/echo_node" in rosapi(ros, "subscribers", topic="/echo/in")["subscribers"]


def test_unadvertise_service_removes_the_ros_service(roslibpy_client, open_bridge, monkeypatch):
    import rospy
    from std_srvs.srv import SetBool

    provider = roslibpy_client()
    seen = []

    def handler(request, response):
        seen.append(request["data"])
        response["success"] = True
        response["message"] = "hosted"
        return True

    service = roslibpy.Service(provider, "/web/unadvertised", "std_srvs/SetBool")
    service.advertise(handler)
    master = master_of(open_bridge.env)
    assert wait_until(lambda: master.lookupService("/web/unadvertised"), 10)
    # a plain ROS client (rospy, no bridge in between) calls the client-hosted service
    monkeypatch.setenv("ROS_MASTER_URI", open_bridge.env.env["ROS_MASTER_URI"])
    reply = rospy.ServiceProxy("/web/unadvertised", SetBool)(True)
    assert reply.success and reply.message == "hosted" and seen == [True]
    assert "/web/unadvertised" in rosapi(provider, "services")["services"]
    service.unadvertise()

    assert wait_until(
        lambda: _service_gone(master, "/web/unadvertised"), 10
    ), "unadvertise_service must unregister the ROS service"
    with pytest.raises(rospy.ServiceException):
        rospy.ServiceProxy("/web/unadvertised", SetBool)(True)
    assert "/web/unadvertised" not in rosapi(provider, "services")["services"]
    assert seen == [True]
    assert provider.is_connected  # the provider's connection lives on


def test_throttle_with_queue_length_keeps_the_newest_of_a_burst(roslibpy_client):
    topic = "/rbd_test/burst"
    throttle = 300  # ms; the burst below reaches the bridge well within one period
    queued, dropped = Inbox(), Inbox()
    roslibpy.Topic(roslibpy_client(), topic, "std_msgs/Int32", throttle_rate=throttle, queue_length=2).subscribe(queued)
    roslibpy.Topic(roslibpy_client(), topic, "std_msgs/Int32", throttle_rate=throttle, queue_length=0).subscribe(
        dropped
    )
    pub = roslibpy.Topic(roslibpy_client(), topic, "std_msgs/Int32")
    assert keep_publishing(pub, lambda i: {"data": -1}, lambda: queued.items and dropped.items)
    # let the warm-up messages drain and a throttle period pass with nothing new
    wait_quiet(queued.count, throttle / 1000.0 + 0.15, 20.0, what="the warm-up messages drained")
    n_queued, n_dropped = queued.count(), dropped.count()
    burst = 10
    for i in range(burst):
        pub.publish(roslibpy.Message({"data": i}))
    assert queued.wait(lambda m: m["data"] == burst - 1, 10), "the newest message of the burst never came"
    assert wait_until(lambda: dropped.count() > n_dropped, 10), "the queue_length=0 subscriber got nothing"
    # nothing more comes on either subscription for a further throttle period
    stays_unchanged(lambda: (queued.count(), dropped.count()), lambda: True, hold=throttle / 1000.0 + 0.1,
                    what="the delivered counts")
    got_queued = [m["data"] for m in queued.items[n_queued:]]
    got_dropped = [m["data"] for m in dropped.items[n_dropped:]]
    # the first goes at once; queue_length=2 keeps the two newest for the next periods
    assert got_queued == [0, burst - 2, burst - 1]
    # queue_length=0: what comes within the period is dropped
    assert got_dropped == [0]


def test_call_service_with_list_args_dict_args_and_missing_args(roslibpy_client):
    ros = roslibpy_client()
    ok = call_raw(ros, {"service": "/echo/set_bool", "args": [True]})
    assert ok == {"result": {"success": True, "message": "echo"}}
    assert call_raw(ros, {"service": "/echo/set_bool", "args": {"data": True}})["result"]["success"] is True
    missing = call_raw(ros, {"service": "/echo/set_bool"})  # no args at all: the request's defaults
    assert missing == {"result": {"success": False, "message": "echo"}}
    assert call_raw(ros, {"service": "/echo/set_bool", "args": []})["result"]["success"] is False
    too_many = call_raw(ros, {"service": "/echo/set_bool", "args": [True, 1]})
    assert "exception" in too_many and "2 arguments" in too_many["exception"]
    # rosapi maps list args by position too
    ros.set_param("/rbd_test/listed", 42)
    value = call_raw(ros, {"service": "/rosapi/get_param", "args": ["/rbd_test/listed", "0"]})
    assert value == {"result": {"value": "42"}}
    default = call_raw(ros, {"service": "/rosapi/get_param", "args": ["/rbd_test/absent", "[7]"]})
    assert default == {"result": {"value": "[7]"}}


def make_fragments(text, size, frag_id):
    total = (len(text) + size - 1) // size
    return [
        {"op": "fragment", "id": frag_id, "data": text[i * size : (i + 1) * size], "num": i, "total": total}
        for i in range(total)
    ]


def reassemble(fragments):
    """Join the fragments of every complete set; return the decoded frames."""
    sets = {}
    for f in fragments:
        sets.setdefault(f["id"], {})[f["num"]] = f
    frames = []
    for parts in sets.values():
        total = next(iter(parts.values()))["total"]
        if len(parts) == total:
            frames.append(json.loads("".join(parts[i]["data"] for i in range(total))))
    return frames


def test_fragments_both_ways_through_roslibpy(roslibpy_client):
    ros = roslibpy_client()
    # in: a publish cut into fragments (sent last-first) reaches ROS and comes back via the echo peer
    echoed = Inbox()
    roslibpy.Topic(ros, "/echo/out", "std_msgs/String").subscribe(echoed)
    text_in = "fragmented " * 20
    frame_in = json.dumps({"op": "publish", "topic": "/echo/in", "msg": {"data": text_in}})
    sets = itertools.count()

    def send_fragmented():
        # (repeated until the echo peer has connected to the bridge's new publisher)
        for part in reversed(make_fragments(frame_in, 25, "in:%d" % next(sets))):
            ros.send_on_ready(roslibpy.Message(part))
        return {"data": text_in} in echoed.items

    # (the check runs right after a send; the next round's step gives the echo time to come back)
    assert wait_until(send_fragmented, 10, step=0.1), echoed.items[:3]
    # out: a subscription with fragment_size gets fragment ops, never a whole publish
    out = roslibpy_client()
    fragments, whole = listen(out, "fragment"), Inbox()
    out.on("/echo/out", whole)
    out.send_on_ready(
        roslibpy.Message(
            {"op": "subscribe", "id": "frag", "topic": "/echo/out", "type": "std_msgs/String", "fragment_size": 16}
        )
    )
    text_out = "back in pieces " * 6
    pub = roslibpy.Topic(ros, "/echo/in", "std_msgs/String")

    def frames_out():
        # the echoes of text_in still on their way (the loop above sends until the first one is
        # back) reach this subscription too: they come in fragments as well, but are not the frame
        return [f for f in reassemble(list(fragments.items)) if f.get("msg", {}).get("data") != text_in]

    assert keep_publishing(pub, lambda i: {"data": text_out}, frames_out)
    frame = frames_out()[0]
    assert frame == {"op": "publish", "topic": "/echo/out", "msg": {"data": text_out}}
    assert all(len(f["data"]) <= 16 for f in fragments.items)
    # a service response with fragment_size comes in fragments as well
    before = len(fragments.items)
    out.send_on_ready(
        roslibpy.Message({"op": "call_service", "id": "t1", "service": "/rosapi/get_time", "fragment_size": 10})
    )
    assert wait_until(lambda: [f for f in reassemble(fragments.items[before:]) if f.get("id") == "t1"], 10)
    reply = [f for f in reassemble(fragments.items[before:]) if f.get("id") == "t1"][0]
    assert reply["op"] == "service_response" and reply["result"] is True
    assert abs(reply["values"]["time"]["secs"] - time.time()) < 5
    assert whole.items == []


def test_status_frames_only_after_set_level_and_filtered_by_level(roslibpy_client):
    quiet, chatty = roslibpy_client(), roslibpy_client()
    quiet_status, chatty_status = listen(quiet, "status"), listen(chatty, "status")
    bad_op = {"op": "no_such_op", "id": "bad"}
    warn_op = {"op": "unadvertise", "id": "warn", "topic": "/never/advertised"}  # a warning
    for ros in (quiet, chatty):
        if ros is chatty:
            ros.set_status_level("error", "lvl")
        ros.send_on_ready(roslibpy.Message(warn_op))
        ros.send_on_ready(roslibpy.Message(bad_op))
        rosapi(ros, "get_time")  # answered after the frames above were handled (same connection)
    assert quiet_status.items == []  # never asked for status: none sent
    assert wait_until(lambda: chatty_status.items, 5)
    assert [(m["level"], m.get("id")) for m in chatty_status.items] == [("error", "bad")]
    assert "no_such_op" in chatty_status.items[0]["msg"]
    chatty.set_status_level("warning", "lvl2")
    chatty.send_on_ready(roslibpy.Message(warn_op))
    assert wait_until(lambda: [m for m in chatty_status.items if m.get("id") == "warn"], 5)
    assert chatty_status.items[-1]["level"] == "warning" and "/never/advertised" in chatty_status.items[-1]["msg"]
    chatty.set_status_level("none", "lvl3")
    chatty.send_on_ready(roslibpy.Message(bad_op))
    rosapi(chatty, "get_time")
    assert len(chatty_status.items) == 2  # level none: silent again


def test_png_compression_through_roslibpy(roslibpy_client):
    ros = roslibpy_client()
    pngs, whole = listen(ros, "png"), Inbox()
    roslibpy.Topic(ros, "/echo/out", "std_msgs/String", compression="png").subscribe(whole)
    pub = roslibpy.Topic(roslibpy_client(), "/echo/in", "std_msgs/String")
    text = "compressed \u00e9 " * 10
    # (this test's own message: an echo of an earlier test's publish may still come in first)
    frames = lambda: [json.loads(png_text(item["data"])) for item in list(pngs.items)]  # noqa: E731
    assert keep_publishing(pub, lambda i: {"data": text}, lambda: [f for f in frames() if f["msg"] == {"data": text}])
    frame = next(f for f in frames() if f["msg"] == {"data": text})
    assert frame == {"op": "publish", "topic": "/echo/out", "msg": {"data": text}}
    assert whole.items == []  # nothing came uncompressed


def test_rosapi_subscribers_search_param_and_action_servers(roslibpy_client):
    ros = roslibpy_client()
    assert rosapi(ros, "subscribers", topic="/echo/in") == {"subscribers": ["/echo_node"]}
    assert rosapi(ros, "subscribers", topic="/no/such/topic") == {"subscribers": []}
    ros.set_param("/rbd_test/searched", 3)
    assert rosapi(ros, "search_param", name="rbd_test/searched") == {"global_name": "/rbd_test/searched"}
    # (the master's upward search matches the first name segment only, so no /rbd_test here)
    assert rosapi(ros, "search_param", name="rbd_no_such_ns/key") == {"global_name": ""}
    ros.delete_param("/rbd_test/searched")
    # an action server's five topics (real actionlib types), and an incomplete set that must not count
    types = {
        "goal": "nav_msgs/GetMapActionGoal",
        "cancel": "actionlib_msgs/GoalID",
        "status": "actionlib_msgs/GoalStatusArray",
        "feedback": "nav_msgs/GetMapActionFeedback",
        "result": "nav_msgs/GetMapActionResult",
    }
    host = roslibpy_client()
    for suffix, type_name in types.items():
        roslibpy.Topic(host, "/rbd_test/get_map/" + suffix, type_name).advertise()
        if suffix in ("goal", "cancel", "status"):
            roslibpy.Topic(host, "/rbd_test/half/" + suffix, type_name).advertise()

    def servers():
        got = []
        ros.get_action_servers(got.append)
        return wait_until(lambda: got, 10)[0]["action_servers"]

    assert wait_until(lambda: "/rbd_test/get_map" in servers(), 10)
    assert "/rbd_test/half" not in servers()
