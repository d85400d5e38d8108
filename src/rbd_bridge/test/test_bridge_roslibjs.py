"""roslibjs (npm ``roslib`` 1.4.1, in Node) against a real bridge.

The npm packages are installed from test/js/package-lock.json with ``npm ci`` when
test/js/node_modules is missing (CI starts bare); without node/npm the test is skipped.
"""

import json
import os
import shutil
import subprocess

import pytest

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


def test_roslibjs_publish_subscribe_services_rosapi(node_ready, open_bridge):
    proc = subprocess.run(  # noqa: UP022 (Python 3.6 has no capture_output)
        [node_ready, os.path.join(JS, "roslibjs_client.js"), open_bridge.url],
        cwd=JS,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        universal_newlines=True,
        timeout=60,
    )
    lines = [line for line in proc.stdout.splitlines() if line.startswith("{")]
    assert proc.returncode == 0 and lines, proc.stdout[-2000:] + proc.stderr[-2000:]
    result = json.loads(lines[-1])
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
