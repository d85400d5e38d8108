"""The link's calls to the robot: the e-stop, the tricks and the preflight (blocking, off the UI thread).

:class:`ServiceCalls` is mixed into :class:`rbd_local.link.RobotLink`, which supplies the connection
(``_ros``, ``connected``, ``address``, ``request_reconnect``, ``wait_connected``).
"""

import concurrent.futures
import logging
import time

import roslibpy
from roslibpy.core import RosTimeoutError

from rbd_local.robot_messages import preflight_report_from_msg, tricks_from_param
from rbd_local.robot_names import (
    EM_STOP_SERVICE,
    PREFLIGHT_MAX_DURATION_S,
    PREFLIGHT_SERVICE,
    PREFLIGHT_SERVICE_TYPE,
    TRICKS_PARAM,
)

LOG = logging.getLogger("rbd_local.link")


class ServiceCalls:
    """Service and parameter calls over the link's current connection."""

    _ros = None

    def em_stop(self, engage: bool, timeout: float = 3.0) -> tuple[bool, str]:
        """Call ``/rbd_controller/em_stop`` (SetBool); blocks the caller up to ``timeout``.

        When the link is down it first asks for an immediate reconnection and waits for it
        (still within ``timeout``). When the connection drops before the answer came (a lossy
        WLAN: the keepalive gave it up), the call is made again on the next connection, still
        within ``timeout``: a SetBool is the same request twice. Nothing is sent once the call
        has returned: the request is never queued for later delivery.

        Args:
            engage: True engages the emergency stop, False releases it.
            timeout: total time allowed [s].

        Returns:
            (success, message) — success is True only if the controller answered success.
        """
        from twisted.internet import reactor  # roslibpy's transport on CPython

        deadline = time.monotonic() + timeout
        dropped = 0  # connections lost with the call in flight
        while True:
            if not self.connected:
                self.request_reconnect()
                if not self.wait_connected(max(0.0, deadline - time.monotonic())):
                    lost = " (%d connection(s) lost during the call)" % dropped if dropped else ""
                    return False, "no connection to %s: e-stop NOT delivered%s" % (self.address, lost)
            ros = self._ros
            if ros is None:
                continue
            answer = concurrent.futures.Future()  # the response's values, or the bridge's error
            service = roslibpy.Service(ros, EM_STOP_SERVICE, "std_srvs/SetBool")
            request = roslibpy.ServiceRequest({"data": bool(engage)})

            def failed(error: object, answer: concurrent.futures.Future = answer) -> None:
                answer.set_exception(RuntimeError(error))

            # sent from the reactor thread, where roslibpy keeps its table of pending calls
            reactor.callFromThread(service.call, request, answer.set_result, failed)
            while not answer.done() and time.monotonic() < deadline and self._ros is ros and ros.is_connected:
                concurrent.futures.wait([answer], timeout=0.02)
            if answer.done():
                try:
                    values = answer.result()
                except RuntimeError as exc:
                    return False, "em_stop call failed: %s" % (exc,)
                return bool(values.get("success", False)), str(values.get("message", ""))
            if time.monotonic() >= deadline:
                return False, "em_stop call failed: no answer within %.1f s: e-stop NOT confirmed" % timeout
            dropped += 1  # the connection is gone with the call: again on the next one
            LOG.warning("link lost with an e-stop call in flight: calling again on the next connection")

    def get_tricks(self, timeout: float = 3.0) -> dict:
        """The robot's tricks, read from ``/rbd_navigation/tricks`` through the bridge's rosapi.

        Blocks the caller up to ``timeout`` (call it off the UI thread). The bridge must
        allow reading the parameter (``params_glob`` of rbd_bridge.launch).

        Returns:
            {trick: [names of its steps]} (see :func:`tricks_from_param`).

        Raises:
            ConnectionError: when the link is down or the bridge does not answer in time.
            ValueError: when the bridge refuses or the value is malformed.
        """
        ros = self._ros
        if ros is None or not self.connected:
            raise ConnectionError("no connection to %s" % self.address)
        try:
            value = roslibpy.Param(ros, TRICKS_PARAM).get(timeout=timeout)
        except RosTimeoutError as exc:
            raise ConnectionError("reading %s timed out after %.1f s" % (TRICKS_PARAM, timeout)) from exc
        except Exception as exc:  # ServiceException (refused by the bridge) or a broken connection
            raise ValueError("reading %s failed: %s" % (TRICKS_PARAM, exc)) from exc
        if value is None:
            raise ValueError("%s is not set on the robot (is rbd_navigation running?)" % TRICKS_PARAM)
        return tricks_from_param(value)

    def run_preflight(self, timeout: float = 20.0, duration: float = 0.0) -> dict:
        """Run the robot's preflight now (``/preflight/run``) and return its report.

        The checks only observe the robot's graph (nothing moves). Blocks the caller up to
        ``timeout`` (call it off the UI thread); the robot observes for ``duration`` and then
        probes the hosts' clocks, so allow several seconds more than ``duration``.

        Args:
            timeout: time allowed for the call [s].
            duration: observation length [s] (0: the robot's default, 3 s; at most 10).

        Returns:
            the report (see :func:`preflight_report_from_msg`).

        Raises:
            ConnectionError: when the link is down or the robot does not answer in time.
            ValueError: when the service is missing or refused (no preflight_server on the
                robot, or the bridge does not allow it) or the answer is malformed.
        """
        if not 0.0 <= duration <= PREFLIGHT_MAX_DURATION_S:
            raise ValueError("duration must be within 0..%g s, got %r" % (PREFLIGHT_MAX_DURATION_S, duration))
        ros = self._ros
        if ros is None or not self.connected:
            raise ConnectionError("no connection to %s: preflight not run" % self.address)
        try:
            service = roslibpy.Service(ros, PREFLIGHT_SERVICE, PREFLIGHT_SERVICE_TYPE)
            response = service.call(roslibpy.ServiceRequest({"duration": float(duration)}), timeout=timeout)
        except RosTimeoutError as exc:
            raise ConnectionError("%s did not answer within %.1f s" % (PREFLIGHT_SERVICE, timeout)) from exc
        except Exception as exc:  # ServiceException: missing or refused; or a broken connection
            raise ValueError("%s failed: %s (is rbd_preflight's preflight_server running and the service in the "
                             "bridge's allow-list?)" % (PREFLIGHT_SERVICE, exc)) from exc
        report = response.get("report") if hasattr(response, "get") else None  # a ServiceResponse (UserDict)
        return preflight_report_from_msg(report)
