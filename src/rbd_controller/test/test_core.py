import pytest

from rbd_controller.core import MainController, Ports
from rbd_controller.fsm import State


class FakeWorld:
    """Fake gestrec, navigation, position controller and publishers."""

    def __init__(self, path=("p1", "p2", "p3")):
        self.gestures = []
        self.path = list(path)
        self.path_ok = True
        self.sent = []
        self.body_poses = []
        self.calls = []  # order of stop-related calls
        self.refuse = False
        self.pos_busy = 0  # ticks until the running pose finishes
        self.pos_stopped = False
        self.estop_flag = None
        self.logs = []
        self.ctl = None
        self.ticks_per_pose = 3
        self.published = 0
        self.t = 0.0

    def ports(self):
        return Ports(
            get_gesture=lambda: self.gestures.pop(0) if self.gestures else "",
            generate_path=self.generate,
            set_position=self.set_position,
            set_body_pose=lambda r, p, h: self.body_poses.append((r, p, h)) or True,
            pos_emergency=lambda on: self.calls.append(("pos_emergency", on)),
            pos_collision=lambda on: self.calls.append(("pos_collision", on)),
            publish_estop=self.publish_estop,
            publish=self.publish,
            log=lambda level, msg: self.logs.append((level, msg)),
        )

    def publish(self, _ctl):
        self.published += 1

    def publish_estop(self, on):
        self.estop_flag = on
        self.calls.append(("estop", on))

    def generate(self, command):
        if command != "walk" or not self.path_ok:
            return False, "unknown command %r" % command, [], []
        return True, "ok", list(self.path), ["name-" + p for p in self.path]

    def set_position(self, pose):
        if self.refuse:
            return False, "refused"
        self.sent.append(pose)
        self.pos_busy = self.ticks_per_pose
        self.ctl.on_pos_status("running")
        return True, "ok"

    def step_pos(self):
        if self.pos_busy > 0:
            self.pos_busy -= 1
            if self.pos_busy == 0:
                self.ctl.on_pos_status("idle")


def make(operator_timeout=0.0, operator_policy="stop", ticks_per_pose=3, lidar_timeout=0.0, **kwargs):
    world = FakeWorld(**kwargs)
    world.ticks_per_pose = ticks_per_pose
    ctl = MainController(
        world.ports(), operator_timeout=operator_timeout, operator_policy=operator_policy, lidar_timeout=lidar_timeout
    )
    world.ctl = ctl
    ctl.start()
    return world, ctl


def release(world, ctl):
    """Release the e-stop and let the first (flushing) gesture poll happen."""
    ctl.set_emergency(False)
    run(world, ctl, 1)


def run(world, ctl, ticks):
    for _ in range(ticks):
        ctl.tick(world.t)
        world.step_pos()
        world.t += 0.25


def test_starts_in_estop_and_publishes_gate():
    world, ctl = make()
    assert ctl.state == State.EMERGENCY_STOP
    assert world.estop_flag is True
    assert ("pos_emergency", True) in world.calls
    run(world, ctl, 5)
    assert world.sent == [] and ctl.state == State.EMERGENCY_STOP


def test_release_sets_attentive_pose_then_gesture_runs_trick_then_waits():
    world, ctl = make()
    world.gestures.append("walk")  # made during the e-stop: dropped
    ctl.set_emergency(False)
    assert world.estop_flag is False
    assert ctl.state == State.WAITING_FOR_GESTURE
    run(world, ctl, 2)
    assert world.gestures == [] and world.sent == []
    assert world.body_poses[0][1] < 0.0  # attentive: pitch nose-up
    world.gestures.append("walk")
    run(world, ctl, 3)
    assert world.body_poses[1] == (0.0, 0.0, 0.0)  # neutral before moving
    run(world, ctl, 20)
    assert world.sent == ["p1", "p2", "p3"]
    assert ctl.state == State.WAITING_FOR_GESTURE
    assert ctl.remaining() == []


def test_unknown_command_goes_back_to_waiting_without_motion():
    world, ctl = make()
    release(world, ctl)
    world.gestures.append("fly")
    run(world, ctl, 5)
    assert ctl.state == State.WAITING_FOR_GESTURE
    assert world.sent == []
    assert any(level == "warn" and "fly" in msg for level, msg in world.logs)


def test_refused_pose_aborts_trick():
    world, ctl = make()
    release(world, ctl)
    world.refuse = True
    world.gestures.append("walk")
    run(world, ctl, 6)
    assert ctl.state == State.WAITING_FOR_GESTURE
    assert any(level == "error" for level, _ in world.logs)


def test_pose_timeout_aborts_trick():
    world, ctl = make()
    ctl.pose_timeout = 2.0
    release(world, ctl)
    world.ticks_per_pose = 1000
    world.gestures.append("walk")
    run(world, ctl, 20)
    assert ctl.state == State.WAITING_FOR_GESTURE
    assert world.sent == ["p1"]


def test_no_running_report_aborts():
    world, ctl = make()
    release(world, ctl)
    world.set_position = lambda pose: (True, "ok")
    ctl.ports.set_position = world.set_position
    world.gestures.append("walk")
    run(world, ctl, 30)
    assert ctl.state == State.WAITING_FOR_GESTURE
    assert any("never reported running" in msg for _, msg in world.logs)


def test_queue_shows_current_then_remaining_names():
    world, ctl = make()
    release(world, ctl)
    world.gestures.append("walk")
    run(world, ctl, 4)
    assert ctl.state == State.EXECUTING
    assert [name for _, name in ctl.remaining()] == ["name-p1", "name-p2", "name-p3"]


def _drive_to(world, ctl, state):
    release(world, ctl)
    if state == State.WAITING_FOR_GESTURE:
        return
    world.gestures.append("walk")
    if state == State.GENERATING_PATH:
        run(world, ctl, 1)
    else:
        run(world, ctl, 4)  # poll, generate, send p1
        world.step_pos()  # p1 half done
    assert ctl.state == state


@pytest.mark.parametrize("state", [State.WAITING_FOR_GESTURE, State.GENERATING_PATH, State.EXECUTING])
@pytest.mark.parametrize("stop", ["estop", "collision"])
def test_preemption_and_resume_from_every_work_state(state, stop):
    world, ctl = make()
    _drive_to(world, ctl, state)
    sent_before = list(world.sent)
    world.calls.clear()
    if stop == "estop":
        ctl.set_emergency(True)
        assert ctl.state == State.EMERGENCY_STOP
        assert world.calls[:2] == [("estop", True), ("pos_emergency", True)]
    else:
        ctl.set_collision(True)
        assert ctl.state == State.COLLISION_DETECTED
        assert world.calls == [("pos_collision", True)]
    # while stopped: no new poses; a gesture made now is dropped after the release
    world.gestures.append("walk")
    run(world, ctl, 10)
    assert world.sent == sent_before
    world.calls.clear()
    if stop == "estop":
        ctl.set_emergency(False)
        assert world.calls == [("estop", False), ("pos_emergency", False)]
    else:
        ctl.set_collision(False)
        assert world.calls == [("pos_collision", False)]
    assert ctl.state == state
    if state == State.WAITING_FOR_GESTURE:
        run(world, ctl, 10)
        assert world.sent == [] and world.gestures == []  # the early gesture was dropped
        world.gestures.append("walk")
    run(world, ctl, 30)
    assert ctl.state == State.WAITING_FOR_GESTURE
    if state == State.EXECUTING:
        # the interrupted pose is re-sent, then the rest
        assert world.sent == ["p1", "p1", "p2", "p3"]
    else:
        assert world.sent == ["p1", "p2", "p3"]


def test_stale_path_result_dropped_after_preemption():
    world, ctl = make()
    release(world, ctl)
    world.gestures.append("walk")
    run(world, ctl, 1)
    assert ctl.state == State.GENERATING_PATH
    original = world.generate

    def generate_and_get_stopped(command):
        ctl.set_emergency(True)  # e-stop arrives while the service call is in flight
        return original(command)

    ctl.ports.generate_path = generate_and_get_stopped
    ctl.tick(world.t)
    assert ctl.state == State.EMERGENCY_STOP
    assert ctl.queue == []


def test_estop_then_collision_then_release_order():
    world, ctl = make()
    _drive_to(world, ctl, State.EXECUTING)
    ctl.set_emergency(True)
    ctl.set_collision(True)
    world.calls.clear()
    ctl.set_emergency(False)
    assert ctl.state == State.COLLISION_DETECTED
    # engage the collision stop before releasing the e-stop
    assert world.calls == [("pos_collision", True), ("estop", False), ("pos_emergency", False)]
    ctl.set_collision(False)
    assert ctl.state == State.EXECUTING


def test_operator_watchdog_off_until_first_heartbeat():
    world, ctl = make(operator_timeout=1.0)
    release(world, ctl)
    world.gestures.append("walk")
    run(world, ctl, 30)
    assert world.sent == ["p1", "p2", "p3"] and ctl.state == State.WAITING_FOR_GESTURE


def _beating_run(world, ctl, ticks, beat=True):
    for _ in range(ticks):
        if beat:
            ctl.on_heartbeat(world.t)
        run(world, ctl, 1)


def test_operator_loss_stops_trick_and_heartbeat_resumes_it():
    world, ctl = make(operator_timeout=1.0, operator_policy="stop", ticks_per_pose=20)
    ctl.on_heartbeat(world.t)
    release(world, ctl)
    world.gestures.append("walk")
    _beating_run(world, ctl, 4)
    assert ctl.state == State.EXECUTING and world.sent == ["p1"]
    world.calls.clear()
    _beating_run(world, ctl, 6, beat=False)  # 1.5 s of silence
    assert ctl.state == State.OPERATOR_LOST
    assert world.calls == [("pos_collision", True)]  # position controller held; e-stop gate untouched
    assert any("operator heartbeat lost" in m for _, m in world.logs)
    world.pos_busy = 0  # the hold dropped the goal
    run(world, ctl, 20)
    assert world.sent == ["p1"] and ctl.state == State.OPERATOR_LOST
    world.calls.clear()
    ctl.on_heartbeat(world.t)
    assert ctl.state == State.EXECUTING and world.calls == [("pos_collision", False)]
    world.ticks_per_pose = 3
    _beating_run(world, ctl, 30)
    assert world.sent == ["p1", "p1", "p2", "p3"] and ctl.state == State.WAITING_FOR_GESTURE


def test_operator_loss_release_acknowledges_and_disarms():
    world, ctl = make(operator_timeout=1.0)
    ctl.on_heartbeat(world.t)
    release(world, ctl)
    _beating_run(world, ctl, 8, beat=False)
    assert ctl.state == State.OPERATOR_LOST
    ctl.set_emergency(False)  # operator acknowledges from the robot side
    assert ctl.state == State.WAITING_FOR_GESTURE
    run(world, ctl, 20)  # disarmed until the next heartbeat
    assert ctl.state == State.WAITING_FOR_GESTURE
    ctl.on_heartbeat(world.t)
    run(world, ctl, 8)
    assert ctl.state == State.OPERATOR_LOST


def test_operator_loss_finish_policy_finishes_trick_then_waits():
    world, ctl = make(operator_timeout=1.0, operator_policy="finish", ticks_per_pose=8)
    ctl.on_heartbeat(world.t)
    release(world, ctl)
    world.gestures.append("walk")
    _beating_run(world, ctl, 3)
    assert ctl.state == State.EXECUTING
    run(world, ctl, 8)  # link lost mid-trick: the trick goes on
    assert ctl.state == State.EXECUTING
    run(world, ctl, 40)
    assert world.sent == ["p1", "p2", "p3"] and ctl.state == State.OPERATOR_LOST
    world.gestures.append("walk")
    run(world, ctl, 10)
    assert world.sent == ["p1", "p2", "p3"]  # no new trick while the operator is gone
    ctl.on_heartbeat(world.t)
    assert ctl.state == State.WAITING_FOR_GESTURE


def test_estop_never_depends_on_operator_link():
    world, ctl = make(operator_timeout=1.0)
    ctl.on_heartbeat(world.t)
    release(world, ctl)
    _beating_run(world, ctl, 8, beat=False)
    assert ctl.state == State.OPERATOR_LOST
    world.calls.clear()
    ctl.set_emergency(True)
    assert ctl.state == State.EMERGENCY_STOP and world.calls[0] == ("estop", True)
    ctl.on_heartbeat(world.t)  # heartbeat back does not release the e-stop
    assert ctl.state == State.EMERGENCY_STOP and world.estop_flag is True


@pytest.mark.parametrize("kwargs", [{"operator_policy": "later"}, {"operator_timeout": float("nan")}])
def test_bad_operator_params_rejected(kwargs):
    with pytest.raises(ValueError):
        make(**kwargs)


def test_lidar_monitor_silence_is_a_collision_until_it_reports_again():
    world, ctl = make(lidar_timeout=0.5, ticks_per_pose=20)
    run(world, ctl, 10)  # never seen: not armed
    assert ctl.state == State.EMERGENCY_STOP
    ctl.on_lidar_state(world.t, False)
    release(world, ctl)
    ctl.on_lidar_state(world.t, False)
    world.gestures.append("walk")
    for _ in range(4):
        ctl.on_lidar_state(world.t, False)
        run(world, ctl, 1)
    assert ctl.state == State.EXECUTING
    world.calls.clear()
    run(world, ctl, 3)  # 0.75 s without a state message
    assert ctl.state == State.COLLISION_DETECTED and world.calls == [("pos_collision", True)]
    assert any("monitor lost" in m for _, m in world.logs)
    ctl.on_lidar_state(world.t, True)  # back, but reporting a collision (stale at start-up)
    assert ctl.state == State.COLLISION_DETECTED
    ctl.set_collision(False)  # rbd_lidar clears through its service as usual
    assert ctl.state == State.EXECUTING


def test_lidar_monitor_back_clear_resumes():
    world, ctl = make(lidar_timeout=0.5)
    ctl.on_lidar_state(world.t, False)
    release(world, ctl)
    run(world, ctl, 4)
    assert ctl.state == State.COLLISION_DETECTED
    ctl.on_lidar_state(world.t, False)
    assert ctl.state == State.WAITING_FOR_GESTURE


def test_remote_estop_engages_during_a_trick_and_blocks_release_while_held():
    world, ctl = make()
    release(world, ctl)
    world.gestures.append("walk")
    run(world, ctl, 4)
    assert ctl.state == State.EXECUTING and world.estop_flag is False
    ctl.set_remote_estop(True)
    assert ctl.state == State.EMERGENCY_STOP and world.estop_flag is True
    assert ("pos_emergency", True) in world.calls  # the same e-stop path as the service
    message = ctl.set_emergency(False)  # the operator releases while the combination is held
    assert "refused" in message and ctl.release_refusal() == message
    assert ctl.state == State.EMERGENCY_STOP and world.estop_flag is True
    ctl.set_remote_estop(False)  # let go: still stopped, only the operator releases
    assert ctl.state == State.EMERGENCY_STOP and ctl.release_refusal() == ""
    ctl.set_emergency(False)
    assert ctl.state == State.EXECUTING and world.estop_flag is False  # resumes the interrupted trick


def test_remote_let_go_alone_releases_nothing():
    world, ctl = make()
    ctl.set_remote_estop(False)
    assert ctl.state == State.EMERGENCY_STOP and world.estop_flag is True
    release(world, ctl)
    ctl.set_remote_estop(False)
    assert ctl.state == State.WAITING_FOR_GESTURE and world.estop_flag is False


# --------------------------------------------------------------------------- issue 27: routing, faults
def test_every_state_is_routed_to_exactly_one_behaviour():
    _, ctl = make()
    owned = [s for b in (ctl.tricks, ctl.stops, ctl.avoidance, ctl.dodging) for s in b.states]
    assert sorted(s.value for s in owned) == sorted(s.value for s in State)
    assert all(s in ctl.routes[s].states for s in State)


def test_a_behaviour_raising_in_tick_engages_the_estop_instead_of_killing_the_node():
    world, ctl = make()
    release(world, ctl)
    real = world.set_position

    def crash_on_second(pose):
        if pose == "p2":
            raise IndexError("list assignment index out of range")
        return real(pose)

    ctl.ports.set_position = crash_on_second
    world.gestures.append("walk")
    run(world, ctl, 12)  # must not raise
    assert ctl.state == State.EMERGENCY_STOP and ctl.faults == 1
    assert world.estop_flag is True and world.calls[-2:] == [("estop", True), ("pos_emergency", True)]
    assert any(level == "error" and "fault in EXECUTING tick" in msg and "IndexError" in msg
               for level, msg in world.logs)
    sent = list(world.sent)
    run(world, ctl, 10)
    assert world.sent == sent  # nothing more is sent while stopped
    ctl.set_emergency(False)  # the release starts over: the crashed trick is not resumed
    run(world, ctl, 10)
    assert ctl.state == State.WAITING_FOR_GESTURE and world.sent == sent and ctl.remaining() == []


def test_a_raising_on_enter_hook_is_an_estop_at_the_next_tick():
    world, ctl = make()
    release(world, ctl)

    def broken(state, previous):
        raise ValueError("broken hook")

    ctl.tricks.on_enter = broken
    world.gestures.append("walk")
    run(world, ctl, 1)  # GESTURE -> GENERATING_PATH: the hook raises inside the tick
    assert ctl.state == State.EMERGENCY_STOP and ctl.faults == 1
    assert any("entering GENERATING_PATH" in msg for _, msg in world.logs)


def test_a_raising_hook_in_a_stop_input_still_tells_the_position_controller():
    world, ctl = make()
    release(world, ctl)

    def broken(state, previous):
        raise ValueError("broken hook")

    ctl.stops.on_enter = broken
    ctl.set_collision(True)  # from the service thread: must not raise, must still hold the robot
    assert ctl.state == State.COLLISION_DETECTED and world.calls[-1] == ("pos_collision", True)
    run(world, ctl, 1)
    assert ctl.state == State.EMERGENCY_STOP and world.estop_flag is True
