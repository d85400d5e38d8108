"""The node refuses to start without a valid gesture mapping."""

import os
import subprocess

NODE = os.path.join(os.path.dirname(__file__), "..", "nodes", "rbd_gestrec")


def test_missing_mapping_stops_node(ros_env):
    proc = subprocess.run(
        ["python3", NODE], env=ros_env.env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=60
    )
    assert proc.returncode != 0
    assert b"invalid configuration" in proc.stdout
