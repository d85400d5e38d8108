"""The one simulator run of tests/experiments (make test): ``run_all --short --parallel --mount-check``.

test_experiments.py reads the thesis experiments from it, test_mount_zone.py the two mounts: the
shipped file measured first on the safety stack (the same sim.launch arguments as mount_zone.py's
stack) and the OS1 centred on the trunk by mount_zone.py after the control stack, in its lane
(at most two stacks at once, as before; one stack start-up fewer, and no run of its own after).
"""

import os
import sys

import pytest
import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from short_run import run_all  # noqa: E402

SHIPPED = os.path.join(os.path.dirname(os.path.dirname(HERE)), "src", "rbd_description", "config", "mounts.yaml")


@pytest.fixture(scope="session")
def short_run(tmp_path_factory):
    """run_all's results.json (with ``stdout``, ``out``) and ``mount_files``: {"back": shipped, "centre": copy}."""
    with open(SHIPPED) as fh:
        centred = yaml.safe_load(fh)
    centred["os_sensor"]["xyz"] = [0.0, 0.0, 0.07]
    centre = str(tmp_path_factory.mktemp("mount_zone") / "centre.yaml")
    with open(centre, "w") as fh:
        yaml.safe_dump(centred, fh)
    for data in run_all(["--short", "--parallel", "--mount-check", centre], 460,
                        keep=os.environ.get("RBD_EXPERIMENTS_OUT")):
        data["mount_files"] = {"back": SHIPPED, "centre": centre}
        yield data
