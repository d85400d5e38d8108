"""The ROS-backed adapters of :class:`rbd_bridge.core.rosapi.RosApi`: master, parameters, types."""

import threading
from typing import Any

import rosgraph
import rospy

from rbd_bridge.ros.msgconv import get_message_class, get_service_class, message_typedefs

__all__ = ["ThreadLocalMaster", "RosParams", "RosTypes"]


class ThreadLocalMaster(threading.local):
    """rosgraph.Master per thread (an XML-RPC ServerProxy must not be shared by threads)."""

    def __init__(self, caller_id: str) -> None:
        """Create the calling thread's master (threading.local runs this again in each thread that uses it)."""
        self.master = rosgraph.Master(caller_id)

    def __getattr__(self, name: str) -> Any:
        """The calling thread's master's attribute (``getTopicTypes``, ``getSystemState``, ...)."""
        return getattr(self.master, name)


class RosParams:
    """The parameter server, as rosapi's parameter calls use it: rospy's own functions."""

    get = staticmethod(rospy.get_param)
    set = staticmethod(rospy.set_param)
    has = staticmethod(rospy.has_param)
    delete = staticmethod(rospy.delete_param)
    search = staticmethod(rospy.search_param)
    names = staticmethod(rospy.get_param_names)


class RosTypes:
    """Message definitions for rosapi (raise ``ConversionError`` for unknown types)."""

    def typedefs(self, type_name: str, part: str = "") -> Any:
        """TypeDef dicts of a message type, or of a service's ``request`` / ``response``."""
        if part:
            return message_typedefs(getattr(get_service_class(type_name), "_%s_class" % part))
        return message_typedefs(get_message_class(type_name))

    def full_text(self, type_name: str) -> str:
        """The full definition text of a message type."""
        return get_message_class(type_name)._full_text
