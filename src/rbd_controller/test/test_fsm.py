import pytest

from rbd_controller.fsm import (
    AVOID_STATES,
    GUARDED_STATES,
    RESUME,
    STOP_STATES,
    TRANSITIONS,
    TRICK_STATES,
    WORK_STATES,
    Event,
    Fsm,
    State,
)

PATH_TO = {
    State.EMERGENCY_STOP: [],
    State.WAITING_FOR_GESTURE: [Event.ESTOP_RELEASE],
    State.GENERATING_PATH: [Event.ESTOP_RELEASE, Event.GESTURE],
    State.EXECUTING: [Event.ESTOP_RELEASE, Event.GESTURE, Event.PATH_READY],
    State.COLLISION_DETECTED: [Event.ESTOP_RELEASE, Event.COLLISION],
    State.OPERATOR_LOST: [Event.ESTOP_RELEASE, Event.OPERATOR_LOST],
    State.BLOCKED: [Event.ESTOP_RELEASE, Event.GESTURE, Event.PATH_READY, Event.COLLISION, Event.BLOCKED_STATIC],
    State.ESCAPING: [Event.ESTOP_RELEASE, Event.GESTURE, Event.PATH_READY, Event.COLLISION, Event.BLOCKED_STATIC,
                     Event.AVOID, Event.COLLISION_CLEAR],
    State.AVOIDING: [Event.ESTOP_RELEASE, Event.GESTURE, Event.PATH_READY, Event.COLLISION, Event.BLOCKED_STATIC,
                     Event.AVOID, Event.COLLISION_CLEAR, Event.ESCAPED],
    State.DODGING: [Event.ESTOP_RELEASE, Event.DODGE],
}
NOT_GUARDED = tuple(s for s in WORK_STATES if s not in GUARDED_STATES)


def fsm_in(state, hooks=None):
    fsm = Fsm(on_enter=hooks)
    for event in PATH_TO[state]:
        # a guarded state only tracks the collision flag (no table entry for its clearing)
        assert fsm.fire(event) or event == Event.COLLISION_CLEAR
    assert fsm.state == state
    return fsm


def test_power_up_is_emergency_stop():
    fsm = Fsm()
    assert fsm.state == State.EMERGENCY_STOP and fsm.estop


def test_values_match_controller_state_msg():
    from rbd_msgs.msg import ControllerState

    for state in State:
        assert getattr(ControllerState, state.name) == state.value, state


@pytest.mark.parametrize("state", list(State))
@pytest.mark.parametrize("event", list(Event))
def test_every_table_entry(state, event):
    fsm = fsm_in(state)
    resume_before = fsm.resume
    collision_before = fsm.collision and event not in (Event.COLLISION_CLEAR,)
    accepted = fsm.fire(event)
    expected = TRANSITIONS.get((state, event))
    assert accepted == (expected is not None)
    if expected is None:
        assert fsm.state == state
    elif expected == RESUME:
        assert fsm.state == resume_before
    elif (collision_before and expected in WORK_STATES and expected not in GUARDED_STATES
          and state not in TRICK_STATES):
        # leaving a stop/guarded state for a trick state with the zone still occupied: stop first
        assert fsm.state == State.COLLISION_DETECTED and fsm.resume == expected
    else:
        assert fsm.state == expected


@pytest.mark.parametrize("state", WORK_STATES)
def test_estop_preempts_and_resumes(state):
    fsm = fsm_in(state)
    fsm.fire(Event.ESTOP)
    assert fsm.state == State.EMERGENCY_STOP and fsm.resume == state
    fsm.fire(Event.COLLISION_CLEAR)  # does not release an e-stop
    assert fsm.state == State.EMERGENCY_STOP
    fsm.fire(Event.ESTOP_RELEASE)
    assert fsm.state == state


@pytest.mark.parametrize("state", NOT_GUARDED)
def test_collision_preempts_and_resumes(state):
    fsm = fsm_in(state)
    fsm.fire(Event.COLLISION)
    assert fsm.state == State.COLLISION_DETECTED and fsm.resume == state
    fsm.fire(Event.ESTOP_RELEASE)  # not an e-stop: nothing happens
    assert fsm.state == State.COLLISION_DETECTED
    fsm.fire(Event.COLLISION_CLEAR)
    assert fsm.state == state


@pytest.mark.parametrize("state", WORK_STATES)
def test_estop_during_collision_keeps_original_resume(state):
    fsm = fsm_in(state)
    fsm.fire(Event.COLLISION)
    fsm.fire(Event.ESTOP)
    assert fsm.state == State.EMERGENCY_STOP and fsm.resume == state
    fsm.fire(Event.ESTOP_RELEASE)  # collision still active
    assert fsm.state == State.COLLISION_DETECTED
    fsm.fire(Event.COLLISION_CLEAR)
    assert fsm.state == state


def test_collision_cleared_while_estop_engaged():
    fsm = fsm_in(State.EXECUTING)
    fsm.fire(Event.COLLISION)
    fsm.fire(Event.ESTOP)
    fsm.fire(Event.COLLISION_CLEAR)
    assert fsm.state == State.EMERGENCY_STOP
    fsm.fire(Event.ESTOP_RELEASE)
    assert fsm.state == State.EXECUTING


def test_collision_during_estop_takes_over_on_release():
    fsm = fsm_in(State.GENERATING_PATH)
    fsm.fire(Event.ESTOP)
    assert fsm.fire(Event.COLLISION)
    assert fsm.state == State.EMERGENCY_STOP
    fsm.fire(Event.ESTOP_RELEASE)
    assert fsm.state == State.COLLISION_DETECTED and fsm.resume == State.GENERATING_PATH


def test_repeated_estop_does_not_overwrite_resume():
    fsm = fsm_in(State.EXECUTING)
    fsm.fire(Event.ESTOP)
    fsm.fire(Event.ESTOP)
    fsm.fire(Event.ESTOP_RELEASE)
    assert fsm.state == State.EXECUTING


def test_normal_cycle_and_hooks():
    entered = []
    hooks = {s: (lambda prev, s=s: entered.append((prev, s))) for s in State}
    fsm = Fsm(on_enter=hooks)
    for event in (Event.ESTOP_RELEASE, Event.GESTURE, Event.PATH_READY, Event.QUEUE_EMPTY):
        fsm.fire(event)
    assert fsm.state == State.WAITING_FOR_GESTURE
    assert entered == [
        (State.EMERGENCY_STOP, State.WAITING_FOR_GESTURE),
        (State.WAITING_FOR_GESTURE, State.GENERATING_PATH),
        (State.GENERATING_PATH, State.EXECUTING),
        (State.EXECUTING, State.WAITING_FOR_GESTURE),
    ]
    assert fsm.epoch == 4


def test_failed_path_and_abort_go_back_to_waiting():
    fsm = fsm_in(State.GENERATING_PATH)
    fsm.fire(Event.PATH_FAILED)
    assert fsm.state == State.WAITING_FOR_GESTURE
    fsm = fsm_in(State.EXECUTING)
    fsm.fire(Event.ABORT)
    assert fsm.state == State.WAITING_FOR_GESTURE


def test_stop_states_reachable_from_every_state():
    for state in State:
        for stop in STOP_STATES:
            event = Event.ESTOP if stop == State.EMERGENCY_STOP else Event.COLLISION
            if state in GUARDED_STATES and event == Event.COLLISION:
                event = Event.ZONE_STALE  # guarded motions stop on the zone per side, and on a stale zone
            fsm = fsm_in(state)
            fsm.fire(event)
            assert fsm.state in STOP_STATES


@pytest.mark.parametrize("state", WORK_STATES)
def test_operator_lost_preempts_and_resumes_on_heartbeat(state):
    fsm = fsm_in(state)
    fsm.fire(Event.OPERATOR_LOST)
    assert fsm.state == State.OPERATOR_LOST and fsm.resume == state and fsm.operator_lost
    fsm.fire(Event.COLLISION_CLEAR)
    assert fsm.state == State.OPERATOR_LOST
    fsm.fire(Event.OPERATOR_BACK)
    assert fsm.state == state and not fsm.operator_lost


def test_release_acknowledges_operator_loss():
    fsm = fsm_in(State.EXECUTING)
    fsm.fire(Event.OPERATOR_LOST)
    fsm.fire(Event.ESTOP_RELEASE)
    assert fsm.state == State.EXECUTING and not fsm.operator_lost


def test_estop_preempts_operator_lost_and_release_resumes_work():
    fsm = fsm_in(State.EXECUTING)
    fsm.fire(Event.OPERATOR_LOST)
    fsm.fire(Event.ESTOP)
    assert fsm.state == State.EMERGENCY_STOP and fsm.resume == State.EXECUTING
    fsm.fire(Event.ESTOP_RELEASE)
    assert fsm.state == State.EXECUTING


def test_collision_and_operator_loss_resume_in_order():
    fsm = fsm_in(State.EXECUTING)
    fsm.fire(Event.COLLISION)
    fsm.fire(Event.OPERATOR_LOST)
    assert fsm.state == State.COLLISION_DETECTED
    fsm.fire(Event.COLLISION_CLEAR)
    assert fsm.state == State.OPERATOR_LOST
    fsm.fire(Event.COLLISION)
    assert fsm.state == State.OPERATOR_LOST
    fsm.fire(Event.OPERATOR_BACK)  # collision still reported
    assert fsm.state == State.COLLISION_DETECTED
    fsm.fire(Event.COLLISION_CLEAR)
    assert fsm.state == State.EXECUTING


# --------------------------------------------------------------------------- issue 17: avoidance
def test_avoidance_cycle_through_the_table():
    entered = []
    hooks = {s: (lambda prev, s=s: entered.append(s)) for s in State}
    fsm = fsm_in(State.EXECUTING, hooks)
    for event in (Event.COLLISION, Event.BLOCKED_STATIC, Event.AVOID, Event.COLLISION_CLEAR, Event.ESCAPED,
                  Event.DETOUR_DONE):
        fsm.fire(event)
    assert entered[-5:] == [State.COLLISION_DETECTED, State.BLOCKED, State.ESCAPING, State.AVOIDING,
                            State.EXECUTING]
    assert fsm.state == State.EXECUTING


def test_blocked_is_a_stop_state_that_waits_for_people_and_resumes_when_clear():
    fsm = fsm_in(State.BLOCKED)
    assert State.BLOCKED in STOP_STATES and fsm.resume == State.EXECUTING
    fsm.fire(Event.OBSTACLE_MOVING)
    assert fsm.state == State.COLLISION_DETECTED and fsm.resume == State.EXECUTING
    fsm.fire(Event.BLOCKED_STATIC)
    fsm.fire(Event.COLLISION_CLEAR)
    assert fsm.state == State.EXECUTING
    assert not fsm_in(State.COLLISION_DETECTED).fire(Event.AVOID)  # no avoidance before it is classified


def test_estop_preempts_blocked_and_release_with_the_obstacle_still_there_classifies_again():
    fsm = fsm_in(State.BLOCKED)
    fsm.fire(Event.ESTOP)
    assert fsm.state == State.EMERGENCY_STOP and fsm.resume == State.EXECUTING
    assert not fsm.fire(Event.AVOID)
    fsm.fire(Event.ESTOP_RELEASE)
    assert fsm.state == State.COLLISION_DETECTED


@pytest.mark.parametrize("state", GUARDED_STATES)
def test_guarded_states_are_not_held_by_the_collision_flag_but_by_everything_else(state):
    fsm = fsm_in(state)
    assert fsm.fire(Event.COLLISION)
    assert fsm.state == state and fsm.collision
    for stop, expect in ((Event.ESTOP, State.EMERGENCY_STOP), (Event.OPERATOR_LOST, State.OPERATOR_LOST),
                         (Event.ZONE_STALE, State.COLLISION_DETECTED)):
        fsm = fsm_in(state)
        fsm.fire(stop)
        assert fsm.state == expect and fsm.resume == state, stop


@pytest.mark.parametrize("state", AVOID_STATES)
def test_avoidance_states_resume_after_an_estop(state):
    fsm = fsm_in(state)
    fsm.fire(Event.ESTOP)
    fsm.fire(Event.ESTOP_RELEASE)
    assert fsm.state == state


def test_moving_obstacle_stops_an_escape():
    fsm = fsm_in(State.ESCAPING)
    fsm.fire(Event.OBSTACLE_MOVING)
    assert fsm.state == State.COLLISION_DETECTED and fsm.resume == State.ESCAPING


@pytest.mark.parametrize("state", [State.ESCAPING, State.AVOIDING])
def test_give_up_returns_to_the_trick(state):
    fsm = fsm_in(state)
    fsm.fire(Event.GIVE_UP)
    assert fsm.state == State.EXECUTING


def test_dodge_cycle_and_dodge_from_a_collision_while_idle():
    fsm = fsm_in(State.WAITING_FOR_GESTURE)
    fsm.fire(Event.DODGE)
    assert fsm.state == State.DODGING
    fsm.fire(Event.DODGE_DONE)
    assert fsm.state == State.WAITING_FOR_GESTURE
    fsm.fire(Event.COLLISION)
    fsm.fire(Event.DODGE)
    assert fsm.state == State.DODGING and fsm.collision
    assert not fsm_in(State.EXECUTING).fire(Event.DODGE)  # never while a trick runs


def test_give_up_while_the_zone_is_occupied_stops_first():
    fsm = fsm_in(State.BLOCKED)
    fsm.fire(Event.GIVE_UP)
    assert fsm.state == State.COLLISION_DETECTED and fsm.resume == State.EXECUTING
    fsm.fire(Event.COLLISION_CLEAR)
    assert fsm.state == State.EXECUTING


def test_escaped_with_the_collision_flag_still_set_waits_for_it_to_clear():
    fsm = fsm_in(State.ESCAPING)
    fsm.fire(Event.COLLISION)
    fsm.fire(Event.ESCAPED)
    assert fsm.state == State.COLLISION_DETECTED and fsm.resume == State.AVOIDING


# --------------------------------------------------------------------------- issue 27: the table against a spec
# Written by hand from DESIGN.md §4 (Fig. 6: e-stop, gesture -> path -> poses, collision preemption and
# resume), §5.1 (power-up e-stop), issue 16 (operator-link watchdog) and issue 17 (avoidance states) --
# NOT derived from TRANSITIONS. Each row: the FSM placed in a state with that state's own stop flags
# (e-stop engaged in EMERGENCY_STOP, zone occupied in COLLISION_DETECTED/BLOCKED, link lost in
# OPERATOR_LOST, none in a work state; a stop interrupted EXECUTING), the event, the state it ends in.
# "back" = the interrupted state (EXECUTING). Every (state, event) pair not listed must change nothing.
ES, WAIT, GEN, EXE = State.EMERGENCY_STOP, State.WAITING_FOR_GESTURE, State.GENERATING_PATH, State.EXECUTING
COLL, LOST, BLK = State.COLLISION_DETECTED, State.OPERATOR_LOST, State.BLOCKED
ESC, AVD, DDG = State.ESCAPING, State.AVOIDING, State.DODGING
E = Event
SPEC = [
    # DESIGN §4: the trick cycle
    (WAIT, E.GESTURE, GEN), (GEN, E.PATH_READY, EXE), (GEN, E.PATH_FAILED, WAIT),
    (EXE, E.QUEUE_EMPTY, WAIT), (EXE, E.ABORT, WAIT),
    # DESIGN §4: the e-stop preempts every state, only an explicit release ends it, then resume
    (ES, E.ESTOP_RELEASE, "back"), (COLL, E.ESTOP, ES), (LOST, E.ESTOP, ES), (BLK, E.ESTOP, ES),
    # DESIGN §4: a collision preempts every state and clears by itself, then resume
    (COLL, E.COLLISION_CLEAR, "back"),
    # issue 16: the operator link; its loss holds like a collision, an e-stop release acknowledges it
    (LOST, E.OPERATOR_BACK, "back"), (LOST, E.ESTOP_RELEASE, "back"),
    # issue 17: classify while stopped; people are waited for; static -> avoid after blocked_timeout
    (COLL, E.BLOCKED_STATIC, BLK), (COLL, E.DODGE, DDG),
    (BLK, E.OBSTACLE_MOVING, COLL), (BLK, E.COLLISION_CLEAR, "back"), (BLK, E.AVOID, ESC),
    (BLK, E.GIVE_UP, COLL),  # the pose is dropped, but the zone is still occupied: stop first
    (ESC, E.ESCAPED, AVD), (ESC, E.GIVE_UP, EXE), (ESC, E.OBSTACLE_MOVING, COLL),
    (AVD, E.DETOUR_DONE, EXE), (AVD, E.GIVE_UP, EXE),
    (WAIT, E.DODGE, DDG), (DDG, E.DODGE_DONE, WAIT),
]
for _work in (WAIT, GEN, EXE, ESC, AVD, DDG):
    SPEC.append((_work, E.ESTOP, ES))
    SPEC.append((_work, E.OPERATOR_LOST, LOST))
    SPEC.append((_work, E.ZONE_STALE, COLL))  # issue 17: a stale zone stops every motion
    if _work not in (ESC, DDG):  # issue 17: the guarded motions are gated per side, not by the flag
        SPEC.append((_work, E.COLLISION, COLL))


def placed(state):
    """An FSM in state with that state's own stop flags; a stop state interrupted EXECUTING."""
    fsm = Fsm(initial=state)
    fsm.collision = state in (COLL, BLK)
    fsm.operator_lost = state == LOST
    fsm.resume = EXE if state in (ES, COLL, LOST, BLK) else WAIT
    return fsm


def test_spec_has_one_row_per_pair():
    pairs = [(s, e) for s, e, _ in SPEC]
    assert len(pairs) == len(set(pairs))


@pytest.mark.parametrize("state,event,expected", SPEC, ids=["%s-%s" % (s.name, e.name) for s, e, _ in SPEC])
def test_table_follows_the_spec(state, event, expected):
    fsm = placed(state)
    fsm.fire(event)
    want = EXE if expected == "back" else expected
    assert fsm.state == want
    if want in (ES, COLL, LOST, BLK) and state not in (ES, COLL, LOST, BLK):
        assert fsm.resume == state  # a work state interrupted by a stop is resumed afterwards
    if state in (ES, COLL, LOST, BLK) and want in (ES, COLL, LOST, BLK):
        assert fsm.resume == EXE  # a stop preempting a stop keeps what to resume


@pytest.mark.parametrize("state", list(State))
def test_every_pair_outside_the_spec_changes_nothing(state):
    listed = {e for s, e, _ in SPEC if s == state}
    for event in Event:
        if event in listed:
            continue
        fsm = placed(state)
        before = (fsm.resume, fsm.epoch)
        fsm.fire(event)
        assert (fsm.state, fsm.resume, fsm.epoch) == (state,) + before, event
