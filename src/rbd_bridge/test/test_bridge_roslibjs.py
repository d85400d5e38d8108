"""roslibjs (npm ``roslib`` 1.4.1, in Node) against a real bridge.

The npm packages are installed from test/js/package-lock.json with ``npm ci`` when
test/js/node_modules is missing (CI starts bare); without node/npm the tests are skipped.
``roslibjs_examples.js`` does what roslibjs's own examples do (test/examples in roslibjs:
pubsub, topic-listener, params, fibonacci, check-topics) and a png subscription, against the
echo peer and the actionlib tutorial's Fibonacci server.
"""

import json
import os
import shutil
import subprocess
import sys

import pytest
from rbd_bridge_testing import FIBONACCI, server_outbound, wait_for_service, wait_until

JS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "js")


@pytest.fixture(scope="module")
def node_ready():
    node, npm = shutil.which("node"), shutil.which("npm")
    if not node or not npm:
        pytest.skip("node/npm not installed")
    if not os.path.isdir(os.path.join(JS, "node_modules", "roslib")):
        proc = subprocess.run(
            [npm, "ci", "--no-audit", "--no-fund"],
            cwd=JS,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            universal_newlines=True,
            timeout=300,
        )
        assert proc.returncode == 0, proc.stdout[-3000:]
    return node


@pytest.fixture(scope="module")
def ros_side(open_bridge):
    """The actionlib tutorial's Fibonacci server beside the echo peer."""
    open_bridge.env.start([sys.executable, FIBONACCI])
    wait_for_service(open_bridge.env, "/fibonacci_server/get_loggers")
    return open_bridge


def run_js(node, script, *args, timeout=120):
    """Run a script of test/js with node; return the JSON line it printed."""
    proc = subprocess.run(  # noqa: UP022 (Python 3.6 has no capture_output)
        [node, os.path.join(JS, script)] + list(args),
        cwd=JS,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        universal_newlines=True,
        timeout=timeout,
    )
    lines = [line for line in proc.stdout.splitlines() if line.startswith("{")]
    assert proc.returncode == 0 and lines, proc.stdout[-2000:] + proc.stderr[-2000:]
    return json.loads(lines[-1])


def test_roslibjs_publish_subscribe_services_rosapi(node_ready, open_bridge):
    result = run_js(node_ready, "roslibjs_client.js", open_bridge.url, timeout=60)
    assert result["echo"] == "from roslibjs"
    assert result["set_bool"] == {"success": True, "message": "echo"}
    assert "always fails" in result["fail"]
    assert result["hosted"] == {"success": False, "message": "js"}
    assert "/echo/tick" in result["topics"]["topics"]
    assert result["topics"]["types"][result["topics"]["topics"].index("/echo/tick")] == "std_msgs/Header"
    assert result["topic_type"] == "std_msgs/Header"
    assert "/echo/set_bool" in result["services"] and "/js/negate" in result["services"]
    assert "/echo_node" in result["nodes"]
    assert result["message_details"][0]["type"] == "std_msgs/Header"
    assert result["param"] == {"n": 42, "s": "x"}
    assert result["time"]["secs"] > 1e9


def test_roslibjs_examples(node_ready, ros_side, roslibpy_client):
    """roslibjs's example behaviours (issue 18 items 1 and 6: publishes right after advertise, unadvertise)."""
    # Every feedback is asserted, and actionlib's feedback is not latched: as in
    # test_rosbridge_compat's fibonacci, the server must already be connected to the bridge's
    # feedback and result subscriptions (shared by all clients) when the goal arrives; a run
    # after test_bridge_raw lost the first feedback. A roslibpy client holds them; the
    # roslibjs goal topic is still advertised and used 100 ms later (what the example proves).
    import roslibpy

    ros = roslibpy_client()
    for name in ("feedback", "result"):
        roslibpy.Topic(ros, "/fibonacci/" + name, "actionlib_tutorials/FibonacciAction" + name.title()).subscribe(
            lambda _m: None
        )
    wanted = {"/fibonacci/feedback", "/fibonacci/result"}
    assert wait_until(lambda: wanted <= server_outbound(ros_side.env, "/fibonacci_server"), 20)
    result = run_js(node_ready, "roslibjs_examples.js", ros_side.url, "examples")
    # pubsub.example: the first publish of one Topic reaches the other's subscription
    assert result["pubsub_first"][:1] == ["Hello Example2!"]
    # topic-listener.example: publishes 50 ms apart from the first one on, all in order
    assert result["listener"] == ["1", "2", "3", "4"]
    # params.examples
    assert result["param_get"] == "bar"
    assert result["param_listed"] is True and result["param_listed_after_delete"] is False
    # fibonacci.example: goal 100 ms after advertise; the tutorial server's feedback and result
    expected = [0, 1, 1, 2, 3, 5, 8, 13, 21]
    assert result["fibonacci_result"] == expected
    assert result["fibonacci_feedback"] == [expected[: n + 3] for n in range(7)]
    # check-topics.example: advertise lists the topic, unadvertise ends it
    assert result["topic_before"] is False and result["topic_advertised"] is True
    assert result["topic_after_unadvertise"] is False


def test_roslibjs_png_compression(node_ready, open_bridge):
    """Issue 18 item 3: roslibjs's png decoding parses the pixels as JSON; the padding must be whitespace."""
    assert run_js(node_ready, "roslibjs_examples.js", open_bridge.url, "png")["png"] == "through a png"


def test_roslibjs_service_readvertised(node_ready, open_bridge):
    """roslibjs's service.test.js (issue 28): the first call after re-advertising reaches the new provider."""
    first, second = run_js(node_ready, "roslibjs_examples.js", open_bridge.url, "service")["service"]
    assert first == {"success": True, "message": "first provider"}
    assert second == {"success": True, "message": "second provider"}
