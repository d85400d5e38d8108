"""Preflight: is the real robot ready? The checks, free of ROS (issue 16).

The collector (:mod:`.collect`, a thin rospy adapter, the only module that imports ROS) watches
the running graph for a few seconds and fills an :class:`Observation` with what it saw: receive
times and header stamps per topic, the last cloud's layout and points, the A1 driver's
diagnostics, transforms, the TF edges with their publishers, the bridge, the clocks of the hosts.
:func:`evaluate` turns that into one :class:`Row` per check: PASS or FAIL with the measured value
and, on FAIL, what to do. A check whose inputs another check already found missing says SKIP and
names that check, so one fault gives one FAIL line (the cause), not a cascade. The command exits 0
only if every row passes.

The facts checked against come from outside this code base: the ouster-ros point layout, the A1
SDK packet sizes and the drivers' rates as ``../shared/INTERFACES.md`` lists them (written here as
literal tables, not imported from rbd_lidar or rbd_a1_driver).

The package, one concept per module: :mod:`.model` (Limits, Stream, Observation, Row), :mod:`.facts`
(the outside facts), :mod:`.rates` (judging a stream), :mod:`.floor` (the floor fit),
:mod:`.sensor_checks` and :mod:`.graph_checks` (the checks), :mod:`.table` (their order and
:func:`evaluate`), :mod:`.render` (the text); :mod:`.clock_probe` reads another host's clock,
:mod:`.collect` fills the observation. This module re-exports the checks' names callers use
(``import rbd_preflight as preflight``); it imports neither ROS nor the collector.
"""

from rbd_preflight.facts import (  # noqa: F401
    A1_DIAG_NAME,
    A1_HIGH_CMD_SIZE,
    A1_OTHER_STATE_SIZES,
    A1_STATE_SIZES,
    DATATYPE_NAMES,
    FEET,
    FOOT_RADIUS,
    MAP_CORRECTION_DIAG,
    NOMINAL_BODY_HEIGHT,
    OS1_ROWS,
    OS1_WIDTHS,
    OUSTER_POINT,
    OUSTER_POINT_STEP,
    size_name,
)
from rbd_preflight.floor import fit_plane, floor_check  # noqa: F401
from rbd_preflight.graph_checks import (  # noqa: F401
    check_bridge,
    check_clocks,
    check_floor,
    check_localized,
    check_pose,
    check_tf_lidar,
    check_tf_parents,
    check_tf_zed2,
    check_zone,
    clock_spread,
    localization_mode,
    tf_clashes,
)
from rbd_preflight.model import FAIL, PASS, SKIP, Limits, Observation, Row, Stream, passed  # noqa: F401
from rbd_preflight.render import format_mount, mounts_in_use, render  # noqa: F401
from rbd_preflight.sensor_checks import (  # noqa: F401
    check_a1_cmd,
    check_a1_layout,
    check_a1_state,
    check_estop,
    check_lidar_cloud,
    check_lidar_imu,
    check_lidar_layout,
    check_zed2,
    covariance_problem,
)
from rbd_preflight.table import CHECKS, evaluate  # noqa: F401
