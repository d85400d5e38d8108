"""pytest plugin of the test kit: the SIGINT guard and the ``ros_env`` fixture.

Loaded by the repository's conftests (``pytest_plugins = ["rbd_testkit.pytest_plugin"]``).
"""

from typing import Iterator

import pytest

from rbd_testkit.process import restore_sigint
from rbd_testkit.ros_env import RosEnv

restore_sigint()


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo) -> Iterator[None]:
    """When a test that uses ``ros_env`` fails, add its processes' last log lines to the report."""
    outcome = yield
    report = outcome.get_result()
    env = getattr(item, "funcargs", {}).get("ros_env")
    if report.failed and isinstance(env, RosEnv) and env.procs:
        report.sections.append(("ros_env process logs (%s)" % report.when, env.tails()))


@pytest.fixture
def ros_env() -> Iterator[RosEnv]:
    """A private ROS master for one test, stopped (with all it started) when the test ends."""
    env = RosEnv()
    try:
        yield env
    finally:
        env.close()
