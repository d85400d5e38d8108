"""roslibpy (the real client library) against a real bridge, master and echo peer."""

import threading
import time

import pytest
import roslibpy
from rbd_bridge_testing import master_of, start_echo, wait_until


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


def keep_publishing(topic, make_msg, until, timeout=10.0, period=0.1):
    """Publish until the predicate holds (subscriptions connect asynchronously in ROS)."""
    deadline = time.monotonic() + timeout
    i = 0
    while time.monotonic() < deadline:
        topic.publish(roslibpy.Message(make_msg(i)))
        i += 1
        if until():
            return True
        time.sleep(period)
    return False


def test_advertise_publish_subscribe_round_trip_through_ros(roslibpy_client):
    ros = roslibpy_client()
    inbox = Inbox()
    out = roslibpy.Topic(ros, "/echo/out", "std_msgs/String")
    out.subscribe(inbox)
    pub = roslibpy.Topic(ros, "/echo/in", "std_msgs/String")
    pub.advertise()
    assert keep_publishing(pub, lambda i: {"data": "hello %d" % i}, lambda: inbox.items)
    assert inbox.items[0]["data"].startswith("hello ")
    pub.unadvertise()
    out.unsubscribe()


def test_publish_without_advertise_infers_the_type(roslibpy_client):
    ros = roslibpy_client()
    inbox = Inbox()
    roslibpy.Topic(ros, "/echo/out", "std_msgs/String").subscribe(inbox)
    deadline = time.monotonic() + 10
    while not inbox.items and time.monotonic() < deadline:
        ros.send_on_ready(roslibpy.Message({"op": "publish", "topic": "/echo/in", "msg": {"data": "no advertise"}}))
        time.sleep(0.1)
    assert inbox.items and inbox.items[0] == {"data": "no advertise"}


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

    def gone():
        try:
            master.lookupService("/web/negate")
            return False
        except Exception:
            return True

    assert wait_until(gone, 10), "the service must be unregistered when its client disconnects"


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
    servers = []
    ros.get_action_servers(servers.append)
    assert wait_until(lambda: servers, 10) and servers[0] == {"action_servers": []}
    pubs = roslibpy.Service(ros, "/rosapi/publishers", "rosapi/Publishers").call(
        roslibpy.ServiceRequest({"topic": "/echo/tick"}), timeout=10
    )
    assert pubs == {"publishers": ["/echo_node"]}
