"""Planning off the tick (issue 27): the planner worker and the avoidance polling it.

The worker runs one job at a time in a thread; the tick polls, never blocks. A slow planner leaves
the robot standing in AVOIDING (nothing sent) while the tick keeps running, a raising planner is a
give-up with its reason (never a dead node), and a result that arrives after the state left
AVOIDING, or after a stop, is dropped.
"""

import math
import threading
import time

import fsm_scenes
import numpy as np
import pytest

from rbd_controller.core import MainController, Ports
from rbd_controller.detour import GridMap
from rbd_controller.fsm import State
from rbd_controller.lattice_plan import LatticePlan
from rbd_controller.perception import AvoidParams
from rbd_controller.planner_worker import PlannerWorker
from rbd_testkit import wait_for


def wait_outcome(worker, timeout=10.0):
    """Poll like the tick does until the wanted job's outcome arrives."""
    return wait_for(worker.poll, timeout, 0.01, what="the job's outcome")


def tick_until(fake, done, timeout=5.0):
    """Tick the fake controller every 10 ms (as the node's timer would) until done() or timeout."""
    def ticked():
        if done():
            return True
        fake.tick()
        return False
    wait_for(ticked, timeout, 0.01)


def test_a_job_runs_off_the_callers_thread_and_its_outcome_is_polled_once():
    worker = PlannerWorker()
    gate = threading.Event()
    seen = []

    def job():
        seen.append(threading.current_thread() is not threading.main_thread())
        gate.wait(5.0)
        return 42

    assert worker.submit("a", job)
    assert worker.poll() is None and worker.busy and worker.pending  # the caller did not wait
    assert not worker.submit("b", lambda: 0)  # one job at a time
    gate.set()
    done = wait_outcome(worker)
    assert (done.key, done.result, done.error) == ("a", 42, "") and seen == [True]
    assert worker.poll() is None and not worker.pending


def test_a_raising_job_is_an_outcome_with_the_error_and_its_trace():
    worker = PlannerWorker()
    assert worker.submit("k", lambda: [][1])
    done = wait_outcome(worker)
    assert done.result is None and done.error.startswith("IndexError") and "Traceback" in done.trace
    assert worker.submit("k2", lambda: 1)  # the worker lives on
    assert wait_outcome(worker).result == 1


def test_a_cancelled_jobs_late_outcome_is_never_delivered():
    worker = PlannerWorker()
    gate = threading.Event()
    assert worker.submit("old", lambda: gate.wait(5.0) and "old plan")
    worker.cancel()
    assert not worker.submit("new", lambda: "new plan")  # the old one still runs: no second planner
    gate.set()
    wait_for(lambda: not worker.busy, 5.0, 0.01)
    assert worker.poll() is None and not worker.busy
    assert worker.submit("new", lambda: "new plan")
    assert wait_outcome(worker).result == "new plan"


class Fake:
    """A controller in AVOIDING towards (2, 0) whose planner job is a stand-in."""

    def __init__(self):
        self.paths = []
        self.logs = []
        self.events = []
        self.ctl = MainController(
            Ports(get_gesture=lambda: "", generate_path=lambda c: (False, "", [], []),
                  set_position=lambda pose: (True, "ok"), set_body_pose=lambda r, p, h: True,
                  pos_emergency=lambda on: None, pos_collision=lambda on: None, publish_estop=lambda on: None,
                  publish=lambda c: None, log=lambda level, msg: self.logs.append((level, msg)),
                  publish_avoidance=self.events.append,
                  follow_path=lambda poses, v: self.paths.append((poses, v)) or (True, "ok")),
            avoid=AvoidParams(static_after=0.5))
        self.ctl.perception.on_pose(0.0, 0.0, 0.0, 0.0)
        self.av = fsm_scenes.avoiding(self.ctl)

    def tick(self):
        self.av._plan_detour(0.0, self.ctl.fsm.epoch)


def straight_plan():
    plan = LatticePlan(True, [(1.0, 0.0, 0.0), (2.0, 0.0, 0.0)], 2.0, 2.0, "test", 0.3)
    plan.speeds, plan.zones = [0.3, 0.3], [(0.9, 0.35, 0.55, 0.35)] * 2
    return "lattice", plan, plan.reason


def test_a_slow_planner_leaves_the_robot_standing_while_the_tick_goes_on():
    fake = Fake()
    gate = threading.Event()
    fake.av._plan_job = lambda *a: gate.wait(5.0) and straight_plan()
    t0 = time.monotonic()
    for _ in range(5):
        fake.tick()
    assert time.monotonic() - t0 < 0.5  # the tick never waited for the planner
    assert fake.ctl.state == State.AVOIDING and fake.av.plan is None and not fake.paths
    gate.set()
    tick_until(fake, lambda: fake.av.plan is not None)
    assert fake.av.kind == "lattice" and fake.av.plan.poses[-1] == (2.0, 0.0, 0.0)
    assert [e for e in fake.events if e["event"] == "plan" and e["planner"] == "lattice"]


def test_a_raising_planner_is_a_give_up_with_its_reason_not_a_dead_node():
    fake = Fake()

    def boom(*a):
        raise ZeroDivisionError("a planner bug")

    fake.av._plan_job = boom
    tick_until(fake, lambda: fake.ctl.state != State.AVOIDING)
    assert fake.ctl.state == State.EXECUTING and fake.ctl.stats["gave_up"] == 1
    assert any(e["event"] == "gave_up" and "ZeroDivisionError: a planner bug" in e["detail"] for e in fake.events)
    assert any(level == "error" and "Traceback" in msg for level, msg in fake.logs)


def test_a_plan_arriving_after_a_stop_is_dropped_and_planned_again():
    fake = Fake()
    gate = threading.Event()
    calls = []
    fake.av._plan_job = lambda *a: calls.append(1) or (gate.wait(5.0) and straight_plan())
    fake.tick()
    ctl = fake.ctl
    before = ctl.fsm.epoch
    ctl.set_emergency(True)  # e-stop while planning: the plan made before it is stale
    assert ctl.state == State.EMERGENCY_STOP
    ctl.set_emergency(False)  # released: back to the detour, under a new epoch
    assert ctl.state == State.AVOIDING and ctl.fsm.epoch != before
    gate.set()
    tick_until(fake, lambda: fake.av.plan is not None)
    assert len(calls) == 2  # the stale plan was dropped and a new one made
    assert fake.av.plan is not None


def test_the_grid_planner_runs_only_when_the_lattice_finds_nothing_and_says_so():
    fake = Fake()
    fake.av.worker = PlannerWorker(inline=True)
    fake.av.lattice.plan = lambda *a, **k: LatticePlan(False, [], 0.0, 2.0, "no path (budget spent)")
    fake.tick()
    fake.tick()
    assert fake.av.kind == "grid" and fake.av.plan.ok
    assert any(level == "warn" and "grid planner" in msg and "budget spent" in msg for level, msg in fake.logs)
    assert [e for e in fake.events if e["event"] == "plan" and e["planner"] == "grid"]


def _degenerate(kind):
    """(robot pose, obstacle points) of a degenerate scene for a blocked pose at (2, 0)."""
    if kind == "start is the goal":
        return (2.0, 0.0, 0.0), np.zeros((0, 2))
    if kind == "start inside the zone":
        return (0.0, 0.0, 0.0), np.array([[0.3, 0.0], [0.3, 0.05]])
    if kind == "goal on the map's edge":
        return (0.0, 0.0, 0.0), np.array([[1.0, 0.9]])
    if kind == "non-finite points":
        return (0.0, 0.0, 0.0), np.array([[math.nan, 0.0], [math.inf, 1.0]])
    return (0.0, 0.0, 0.0), np.zeros((0, 2))  # no points, no map


@pytest.mark.parametrize("kind", ["start is the goal", "start inside the zone", "goal on the map's edge",
                                  "non-finite points", "empty"])
def test_degenerate_scenes_give_a_detour_or_a_reason_never_a_crash(kind):
    fake = Fake()
    fake.av.worker = PlannerWorker(inline=True)
    fake.av.budget = 2.0
    pose, points = _degenerate(kind)
    fake.ctl.perception.on_pose(0.0, *pose)
    fake.ctl.perception.on_blocking_points(0.0, [tuple(p) for p in points])
    if kind == "goal on the map's edge":  # a 2 x 2 m map ending at the goal's x, one wall cell on it
        occupied = np.zeros((40, 40), dtype=bool)
        occupied[20, 39] = occupied[0, 0] = True
        fake.ctl.perception.on_map(GridMap(occupied, (0.0, -1.0), 0.05))
    for _ in range(3):
        fake.tick()
    assert not [m for level, m in fake.logs if "planner crashed" in m], fake.logs
    assert fake.av.plan is not None or fake.ctl.state != State.AVOIDING, (kind, fake.logs)
