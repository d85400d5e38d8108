"""The node refuses to start on an invalid tricks file (fail fast), with a clear message."""

import os
import subprocess

import pytest

NODE = os.path.join(os.path.dirname(__file__), "..", "nodes", "rbd_navigation")


def run_node(ros_env, *args):
    return subprocess.run(
        ["python3", NODE] + list(args),
        env=ros_env.env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        universal_newlines=True,
        timeout=60,
    )


@pytest.mark.parametrize(
    "content, fragment",
    [
        ("tricks:\n  walk:\n    - {x: 0.6}\n", "name"),
        ("tricks: [", "while parsing"),
        ("tricks:\n  walk:\n    - {name: a, roll: 2.0}\n", "limit"),
    ],
)
def test_invalid_tricks_file_stops_node(ros_env, tmp_path, content, fragment):
    bad = tmp_path / "tricks.yaml"
    bad.write_text(content)
    proc = run_node(ros_env, "_tricks_file:=%s" % bad)
    assert proc.returncode != 0
    assert "invalid tricks configuration" in proc.stdout and fragment in proc.stdout


def test_missing_tricks_stops_node(ros_env):
    proc = run_node(ros_env)
    assert proc.returncode != 0
    assert "no tricks" in proc.stdout
