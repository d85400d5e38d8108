"""What the controller's behaviours share: the ports, the FSM, the last goal, the avoidance episode. ROS-free.

Each behaviour (:mod:`tricks`, :mod:`stops`, :mod:`avoidance`, :mod:`dodging`) owns its own state;
what more than one of them reads or writes lives here, in :class:`Context`: the outside world
(:class:`Ports`), the FSM and its lock, the goal last sent to the position controller
(:class:`Goal`), the avoidance episode and its no-progress clock (:class:`Episode`), the show's
home, the avoidance counters and whether the robot is localized in a loaded map.
"""

import threading
from typing import Any, Callable, List, Optional, Sequence, Tuple

from rbd_controller.detour import zone_occupied_at
from rbd_controller.fsm import Event, State
from rbd_controller.perception import AvoidParams, Perception
from rbd_msgs.msg import PosControllerStatus

PathResult = Tuple[bool, str, Sequence[Any], Sequence[str]]


class Ports:
    """What the controller needs from the outside world (ROS in the node, fakes in tests).

    Every callable must not raise; failures are reported through return values.

    Args:
        get_gesture: () -> command or "" (GetLastGesture).
        generate_path: command -> (success, message, poses, names) (GeneratePath).
        set_position: pose -> (accepted, message) (SetPosition).
        set_body_pose: (roll, pitch, body_height) -> bool (SetBodyPose).
        pos_emergency: bool -> None: tell the position controller about the e-stop.
        pos_collision: bool -> None: tell the position controller about a collision.
        publish_estop: bool -> None: the latched e-stop flag the driver gates on.
        publish: controller -> None: publish state, queue, path (called after changes).
        log: (level, message) -> None, level in "info", "warn", "error".
        set_guarded_position: (x, y, max_speed) -> (accepted, message) (SetGuardedPosition).
        make_pose: (x, y, yaw) -> a pose for set_position (geometry_msgs/Pose in the node).
        pose_xy: pose -> (x, y, yaw) of a trick pose.
        publish_avoidance: dict -> None: avoidance events, plans and the arena (RViz, reports).
        follow_path: ([(x, y, yaw), ...], max_speed) -> (accepted, message) (FollowPath: the detour).
    """

    def __init__(
        self,
        get_gesture: Callable[[], str],
        generate_path: Callable[[str], PathResult],
        set_position: Callable[[Any], Tuple[bool, str]],
        set_body_pose: Callable[[float, float, float], bool],
        pos_emergency: Callable[[bool], None],
        pos_collision: Callable[[bool], None],
        publish_estop: Callable[[bool], None],
        publish: Callable[[Any], None],
        log: Callable[[str, str], None],
        set_guarded_position: Callable[[float, float, float], Tuple[bool, str]] = None,
        make_pose: Callable[[float, float, float], Any] = None,
        pose_xy: Callable[[Any], Tuple[float, float, float]] = None,
        publish_avoidance: Callable[[dict], None] = None,
        follow_path: Callable[[List[Tuple[float, float, float]], float], Tuple[bool, str]] = None,
    ) -> None:
        self.get_gesture = get_gesture
        self.generate_path = generate_path
        self.set_position = set_position
        self.set_body_pose = set_body_pose
        self.pos_emergency = pos_emergency
        self.pos_collision = pos_collision
        self.publish_estop = publish_estop
        self.publish = publish
        self.log = log
        self.set_guarded_position = set_guarded_position or (lambda x, y, v: (False, "no guarded motion"))
        self.make_pose = make_pose or (lambda x, y, yaw: (x, y, yaw))
        self.pose_xy = pose_xy or (lambda pose: (pose[0], pose[1], pose[2]))
        self.publish_avoidance = publish_avoidance or (lambda info: None)
        self.follow_path = follow_path or (lambda poses, v: (False, "no path follower"))


class Goal:
    """The goal last sent to the position controller and what its status messages said since.

    Args:
        start_timeout: time for the position controller to report "running" after accepting [s].
    """

    def __init__(self, start_timeout: float) -> None:
        self.start_timeout = start_timeout
        self.sent_at = None  # type: Optional[float]
        self.seen_running = False
        self.status_seq = 0
        self.status = ""
        self.sent_seq = 0

    def on_status(self, status: str) -> None:
        """A status message (idle/running/emergency/collision) from the position controller."""
        self.status_seq += 1
        self.status = status
        if status == PosControllerStatus.RUNNING and self.status_seq > self.sent_seq:
            self.seen_running = True

    def sending(self) -> None:
        """A goal is about to be sent: only later status messages count for it."""
        self.sent_seq = self.status_seq
        self.seen_running = False

    def done(self) -> bool:
        """The position controller went running -> idle since the goal was sent."""
        return self.seen_running and self.status == PosControllerStatus.IDLE

    def result(self, now: float, timeout: float) -> str:
        """"none", "active", "done" or "failed" for the last goal sent (done/failed forget it)."""
        if self.sent_at is None:
            return "none"
        if self.done():
            self.sent_at = None
            return "done"
        if (not self.seen_running and now - self.sent_at > self.start_timeout) or now - self.sent_at > timeout:
            self.sent_at = None
            return "failed"
        return "active"


class Episode:
    """One avoidance episode (first BLOCKED/ESCAPING/AVOIDING until the blocked pose is reached or dropped).

    ``active`` counts the seconds spent in BLOCKED, ESCAPING and AVOIDING; ``progress`` is its value at
    the last progress (an escape that cleared the zone, a detour pose reached).
    """

    def __init__(self) -> None:
        self.start = None  # type: Optional[float]
        self.trick_since = None  # type: Optional[float]  # first episode of this trick
        self.active = 0.0
        self.progress = 0.0

    def begin(self, now: float) -> None:
        """An avoidance state was entered: start the episode unless one runs."""
        if self.start is None:
            self.start = now
            self.progress = self.active
            if self.trick_since is None:
                self.trick_since = now

    def progressed(self) -> None:
        """Progress: restart the no-progress clock."""
        self.progress = self.active

    def stalled(self, timeout: float) -> bool:
        """An episode runs and made no progress for more than timeout active seconds."""
        return self.start is not None and self.active - self.progress > timeout


class Context:
    """The state shared by the behaviours (the FSM is attached by the controller).

    Args:
        ports: the outside world.
        avoid: active collision avoidance parameters.
        start_timeout: see :class:`Goal`.
    """

    def __init__(self, ports: Ports, avoid: AvoidParams, start_timeout: float) -> None:
        self.ports = ports
        self.avoid = avoid
        self.perception = Perception(avoid)
        self.lock = threading.RLock()
        self.fsm = None  # type: Optional[Fsm]
        self.controller = None  # type: Any  # what ports.publish gets (set by the controller)
        self.goal = Goal(start_timeout)
        self.episode = Episode()
        self.stats = {"avoided": 0, "gave_up": 0, "escapes": 0, "dodges": 0, "blocked": 0}  # type: Dict[str, int]
        self.home = None  # type: Optional[Tuple[float, float]]  # where the show is (dodge, arena, back home)
        self.home_yaw = None  # type: Optional[float]
        self.reason = ""  # why the last avoidance event fired (published when BLOCKED is entered)
        self.localized = None  # type: Optional[bool]  # latest /rbd_localization/localized (None: none yet)
        self.now = 0.0  # latest time seen by tick()/on_heartbeat()
        self.lidar_lost = False
        self._synced = (None, None)  # (emergency, collision) told to the position controller

    def sync_stops(self) -> None:
        """Tell the driver gate and the position controller; engage before release.

        OPERATOR_LOST holds the position controller like a collision does (it drops its
        goal and stops; the interrupted pose is re-sent on resume). It never touches the
        e-stop gate.
        """
        emergency = self.fsm.state == State.EMERGENCY_STOP
        collision = self.fsm.state in (State.COLLISION_DETECTED, State.OPERATOR_LOST, State.BLOCKED)
        old_emergency, old_collision = self._synced
        if emergency != old_emergency and emergency:
            self.ports.publish_estop(True)
            self.ports.pos_emergency(True)
        if collision != old_collision and collision:
            self.ports.pos_collision(True)
        if emergency != old_emergency and not emergency:
            self.ports.publish_estop(False)
            self.ports.pos_emergency(False)
        if collision != old_collision and not collision:
            self.ports.pos_collision(False)
        self._synced = (emergency, collision)

    def publish(self) -> None:
        """Publish the controller's state, queue and path (ports.publish gets the controller)."""
        self.ports.publish(self.controller)

    def fire(self, event: Event) -> None:
        """Caller holds the lock. Fire event, tell the stops, publish."""
        self.fsm.fire(event)
        self.sync_stops()
        self.publish()

    def fire_if(self, epoch: int, event: Event) -> bool:
        """Fire event only if nothing changed the FSM since epoch (caller holds the lock)."""
        if self.fsm.epoch != epoch:
            return False
        self.fire(event)  # avoidance events move between stop and motion states
        return True

    def may_avoid(self, now: float) -> bool:
        """Avoidance may move the robot: zone fresh and valid, monitor alive, operator present."""
        p = self.perception
        reading, t = p.reading, p.reading_time
        return (
            reading is not None
            and reading.valid
            and t is not None
            and now - t <= 0.5
            and p.pose is not None
            and not self.lidar_lost
            and not self.fsm.operator_lost
        )

    def goal_blocked(self, pose: Any, points: Any) -> int:
        """Known obstacle points inside the stop zone of a robot at the trick pose."""
        return zone_occupied_at(self.ports.pose_xy(pose), self.avoid.zone, points)

    def known_obstacles(self, since: Optional[float] = None) -> Any:
        """Caller holds the lock. The remembered obstacle points from 5 s before since (default: this episode)."""
        if since is None:
            since = self.episode.start if self.episode.start is not None else self.now
        return self.perception.obstacles(since - 5.0)


class Behaviour:
    """A part of the controller that owns the FSM states it routes: its own state, on_enter and tick.

    Args:
        ctx: the shared context.
    """

    #: The FSM states this behaviour handles.
    states = ()  # type: Tuple[State, ...]

    def __init__(self, ctx: Context) -> None:
        self.ctx = ctx

    def on_enter(self, state: State, previous: State) -> None:
        """The FSM entered state (one of :attr:`states`) from previous; called with the lock held."""

    def tick(self, state: State, now: float, epoch: int) -> None:
        """One step in state (called from the loop thread without the lock)."""
