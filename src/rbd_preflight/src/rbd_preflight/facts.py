"""Facts the preflight checks compare against, from outside this code base (INTERFACES.md)."""

#: ouster-ros ``point_type:=original`` (INTERFACES.md §1, master ``include/ouster_ros/os_point.h``):
#: field -> (offset [B], PointField datatype). ring is UINT16 (4) since v0.7.1, UINT8 (2) before.
OUSTER_POINT = {
    "x": (0, (7,)),
    "y": (4, (7,)),
    "z": (8, (7,)),
    "intensity": (16, (7,)),
    "t": (20, (6,)),
    "reflectivity": (24, (4,)),
    "ring": (26, (4, 2)),
    "ambient": (28, (4,)),
    "range": (32, (6,)),
}
OUSTER_POINT_STEP = 48
OS1_ROWS = 32
#: columns_per_frame of the OS1 modes (512x10 ... 4096x5).
OS1_WIDTHS = (512, 1024, 2048, 4096)
DATATYPE_NAMES = {1: "INT8", 2: "UINT8", 3: "INT16", 4: "UINT16", 5: "INT32", 6: "UINT32", 7: "FLOAT32", 8: "FLOAT64"}
#: Unitree SDK HighState sizes on LCM_High_State (INTERFACES.md §2) -> SDK release.
A1_STATE_SIZES = {265: "SDK v3.3/v3.3.1", 1025: "SDK 3.3.3/3.3.4"}
#: Sizes of other releases, for the message (v3.2: 256 B, v3.3.2: 319 B).
A1_OTHER_STATE_SIZES = {256: "SDK v3.2", 319: "SDK v3.3.2"}
A1_HIGH_CMD_SIZE = 113
#: The driver's diagnostics status preflight reads (rbd_a1_driver README, "the diagnostics contract").
A1_DIAG_NAME = "rbd_a1_driver: A1 link"
#: rbd_localization's map correction diagnostics task (README "Published Topics"; diagnostic_updater
#: puts the node's name in front: ``map_correction: Map correction``). Its ``mode`` value is
#: ``mapping`` or ``localization (FILE)``.
MAP_CORRECTION_DIAG = "Map correction"
#: The A1's foot spheres (a1_description): the floor is one radius below a foot frame.
FOOT_RADIUS = 0.02
FEET = ("FR_foot", "FL_foot", "RR_foot", "RL_foot")
#: The A1's nominal standing height (SDK default bodyHeight 0.28 m): the floor without foot frames.
NOMINAL_BODY_HEIGHT = 0.28


def size_name(size: int) -> str:
    """``1025 B (SDK 3.3.3/3.3.4)``, ``300 B (unknown)``."""
    if size in A1_STATE_SIZES:
        return "%d B (%s)" % (size, A1_STATE_SIZES[size])
    if size in A1_OTHER_STATE_SIZES:
        return "%d B (%s, not supported)" % (size, A1_OTHER_STATE_SIZES[size])
    return "%d B (unknown)" % size
