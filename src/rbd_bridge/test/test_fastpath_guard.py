"""Issue 28: ``~rospy_fast_path`` engages only on the rospy internals it was written for.

``fastpath.rospy_unfit`` checks them at start (the replaced methods by arity, the attributes
of a TCPROS connection that are read); on anything else the backend logs one warning and runs
on plain rospy.
"""

import asyncio

import rospy
import rospy.topics
from rospy.impl.tcpros_base import TCPROSTransport

from rbd_bridge.core.security import Policy
from rbd_bridge.ros import backend as backend_module
from rbd_bridge.ros.fastpath import FastPath, rospy_unfit


def test_the_installed_rospy_fits():
    assert rospy_unfit() == ""


def test_a_receive_loop_with_other_arguments_does_not_fit(monkeypatch):
    monkeypatch.setattr(TCPROSTransport, "receive_loop", lambda self, callback, extra: None)
    assert "arities [2, 1, 2, 2]" in rospy_unfit()


def test_a_connection_without_read_buff_does_not_fit(monkeypatch):
    init = TCPROSTransport.__init__

    def without_read_buff(self, *args, **kwargs):
        init(self, *args, **kwargs)
        del self.read_buff

    monkeypatch.setattr(TCPROSTransport, "__init__", without_read_buff)
    assert "missing ['read_buff']" in rospy_unfit()


def test_a_missing_private_class_does_not_fit(monkeypatch):
    monkeypatch.delattr(rospy.topics, "_SubscriberImpl")
    assert rospy_unfit().startswith("ImportError")


def _backend(monkeypatch, unfit):
    warnings = []
    monkeypatch.setattr(backend_module, "rospy_unfit", lambda: unfit)
    monkeypatch.setattr(rospy, "logwarn", lambda *args: warnings.append(args[0] % args[1:]))
    loop = asyncio.new_event_loop()
    try:
        backend = backend_module.RosBackend(loop, Policy())
    finally:
        loop.close()
    backend.services.pool.shutdown(wait=False)
    return backend, warnings


def test_the_backend_falls_back_to_plain_rospy_with_one_warning(monkeypatch):
    backend, warnings = _backend(monkeypatch, "arities [2, 1, 2, 2], missing []")
    assert backend.fast is None and backend.topics.fast is None
    assert backend.stats()["rospy_fast_path"] is False
    assert len(warnings) == 1 and "~rospy_fast_path off" in warnings[0] and "arities" in warnings[0]


def test_the_backend_takes_the_fast_path_when_rospy_fits(monkeypatch):
    backend, warnings = _backend(monkeypatch, "")
    assert isinstance(backend.fast, FastPath) and backend.topics.fast is backend.fast
    assert backend.stats()["rospy_fast_path"] is True and warnings == []
