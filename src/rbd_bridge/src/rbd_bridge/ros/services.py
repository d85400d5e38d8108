"""Services: ``call_service`` into ROS (and rosapi) in a thread pool; services hosted by clients."""

import concurrent.futures
import itertools
import logging
import socket
import threading
from typing import Any, Callable, Optional

import rospy
import rosservice

from rbd_bridge.core.rosapi import RosApi, RosApiError
from rbd_bridge.core.types import BridgeError, ConversionError, normalize_type
from rbd_bridge.ros.msgconv import dict_to_msg, get_service_class, msg_to_dict

__all__ = ["Services"]

_log = logging.getLogger("rbd_bridge")


def _is_transport_error(exc: Exception) -> bool:
    text = str(exc).lower()
    kinds = (rospy.exceptions.TransportException, socket.error, EOFError)
    return isinstance(exc, kinds) or "transport error" in text or "unable to connect" in text or "connection" in text


class _Hosted:
    """A service that a WebSocket client provides to ROS (registered with it)."""

    def __init__(self, services: Any, name: str, type_name: str, cls: Any, session: Any) -> None:
        self.services, self.name, self.type, self.cls, self.session = services, name, type_name, cls, session
        self.pending, self.lock, self.closed, self.false_logged = {}, threading.Lock(), False, False
        self.server = rospy.Service(name, cls, self.handle)

    def handle(self, request: Any) -> Any:
        """Rospy thread: forward the request to the client and wait for its answer."""
        call_id = "service_request:%s:%d" % (self.name, next(self.services.ids))
        answer = concurrent.futures.Future()
        with self.lock:
            if self.closed:
                raise rospy.ServiceException("service %s: its WebSocket provider is gone" % self.name)
            self.pending[call_id] = answer
        values = msg_to_dict(request)
        self.services.loop.call_soon_threadsafe(self.session.send_service_request, self.name, call_id, values)
        timeout = self.services.service_timeout
        try:
            ok, values = answer.result(timeout)
        except concurrent.futures.TimeoutError:
            with self.lock:
                self.pending.pop(call_id, None)
            text = "service %s: WebSocket provider did not answer in %.1f s" % (self.name, timeout)
            raise rospy.ServiceException(text) from None
        if not ok and not isinstance(values, dict):
            raise rospy.ServiceException("service %s failed: %s" % (self.name, values))
        if not ok and not self.false_logged:  # (Session._op_service_response says why)
            self.false_logged = True
            _log.warning("service %s: provider answered result=false; values passed on as by rosbridge", self.name)
        try:
            response, _ = dict_to_msg(self.cls._response_class, values if isinstance(values, dict) else {})
        except ConversionError as exc:
            text = "service %s: bad response from its WebSocket provider: %s" % (self.name, exc)
            raise rospy.ServiceException(text) from None
        return response

    def answer(self, call_id: Any, ok: bool, values: Any) -> bool:
        with self.lock:
            answer = self.pending.pop(call_id, None)
        if answer is not None:
            answer.set_result((ok, values))
        return answer is not None

    def close(self, reason: str) -> None:
        with self.lock:
            self.closed = True
            pending, self.pending = self.pending, {}
        for answer in pending.values():
            answer.set_result((False, reason))
        self.server.shutdown(reason)


class Services:
    """``call_service`` and client-hosted services for the backend (answers come back on the loop).

    ``rosapi`` (:class:`rbd_bridge.core.rosapi.RosApi`) answers ``/rosapi/*``; a ROS caller
    waits ``service_timeout`` s for a client-hosted service; ``call_service`` without
    ``timeout`` gives up after ``call_timeout`` s (0 = never).
    """

    def __init__(self, loop: Any, master: Any, service_timeout: float = 10.0, call_timeout: float = 30.0) -> None:
        self.loop, self.master, self.service_timeout, self.call_timeout = loop, master, service_timeout, call_timeout
        self.rosapi = None  # (the backend's RosApi, which needs service_type)
        self.pool = concurrent.futures.ThreadPoolExecutor(max_workers=8, thread_name_prefix="rbd_bridge_call")
        self.hosted, self.ids, self._types = {}, itertools.count(1), {}
        self._proxies, self._proxy_lock = {}, threading.Lock()  # service -> (type, persistent proxy, lock)

    def call_service(
        self, session: Any, service: str, args: Any, timeout: Optional[float], done: Callable[..., Any]
    ) -> None:
        """Run the call in the pool; ``done(ok, values)`` is called on the loop (at most once)."""
        answered = []

        def finish(ok: bool, values: Any) -> None:
            if handle is not None:
                handle.cancel()
            if not answered:
                answered.append(ok)
                done(ok, values)

        timeout = timeout or self.call_timeout
        text = "service %s: no response within %.1f s" % (service, timeout)
        handle = self.loop.call_later(timeout, finish, False, text) if timeout else None

        call = self.rosapi.call if RosApi.handles(service) else self._call_ros

        def work() -> None:
            try:
                result = (True, call(service, args))
            except (RosApiError, BridgeError, ConversionError) as exc:
                result = (False, str(exc))
            except Exception as exc:  # rospy raises a zoo of types
                result = (False, "service %s failed: %s" % (service, exc))
            self.loop.call_soon_threadsafe(finish, *result)

        self.pool.submit(work)

    def service_type(self, service: str) -> str:
        """The type of a ROS service (hosted ones included); raises BridgeError if it does not exist."""
        type_name = self._types.get(service)
        if type_name is None:
            hosted = self.hosted.get(service)
            type_name = hosted.type if hosted is not None else rosservice.get_service_type(service)
            if not type_name:
                raise BridgeError("service %s does not exist" % service)
            self._types[service] = type_name
        return type_name

    def _call_ros(self, service: str, args: Any) -> Any:
        try:
            type_name = self.service_type(service)
            cls = get_service_class(type_name)
            fields = cls._request_class.__slots__
            if isinstance(args, list):  # by field order
                if len(args) > len(fields):
                    raise ConversionError("%d arguments given, request has %d fields" % (len(args), len(fields)))
                args = dict(zip(fields, args))
            request = dict_to_msg(cls._request_class, args, rospy.Time.now)[0]
        except (rosservice.ROSServiceIOException, ConversionError) as exc:
            raise BridgeError("service %s: %s" % (service, exc)) from None
        with self._proxy_lock:
            entry = self._proxies.get(service)
            fresh = entry is None or entry[0] != type_name
            if fresh:
                entry = (type_name, rospy.ServiceProxy(service, cls, persistent=True), threading.Lock())
                self._proxies[service] = entry
        _, proxy, lock = entry
        if not lock.acquire(False):
            # a call on the persistent connection is in flight: use a one-shot connection
            return msg_to_dict(rospy.ServiceProxy(service, cls).call(request))
        try:
            try:
                response = proxy.call(request)
            except Exception as exc:
                with self._proxy_lock:
                    if self._proxies.get(service) is entry:
                        del self._proxies[service]
                self._types.pop(service, None)
                if fresh or not _is_transport_error(exc):
                    raise
                # the provider restarted since the connection was made: retry once on a new one
                response = rospy.ServiceProxy(service, cls).call(request)
        finally:
            lock.release()
            if self._proxies.get(service) is not entry:  # failed, or unhosted meanwhile: not reused
                proxy.close()
        return msg_to_dict(response)

    def advertise_service(self, session: Any, service: str, type_name: str) -> None:
        """Serve service in ROS on behalf of session."""
        type_name = normalize_type(type_name)  # (ConversionError: Session names the op)
        cls = get_service_class(type_name)
        hosted = self.hosted.get(service)
        if hosted is not None:
            if hosted.session is not session:
                raise BridgeError("advertise_service: %s is already provided by another client" % service)
            self._unhost(hosted, "re-advertised")
        else:
            try:
                uri = self.master.lookupService(service)
            except Exception:
                uri = None
            if uri:
                raise BridgeError("advertise_service: %s is already provided in ROS (%s)" % (service, uri))
        self.hosted[service] = _Hosted(self, service, type_name, cls, session)
        self._types.pop(service, None)

    def _unhost(self, hosted: Any, reason: str) -> None:
        if self.hosted.get(hosted.name) is hosted:
            del self.hosted[hosted.name]
        self._types.pop(hosted.name, None)
        hosted.close(reason)
        with self._proxy_lock:  # rospy keeps serving a persistent connection after shutdown:
            entry = self._proxies.pop(hosted.name, None)  # drop it, or a re-advertised service's
        if entry is not None and entry[2].acquire(False):  # first call reaches the old provider
            entry[1].close()  # (a call in flight gets its answer, then closes it itself)
            entry[2].release()

    def unadvertise_service(self, session: Any, service: str) -> None:
        """Stop serving service for session."""
        hosted = self.hosted.get(service)
        if hosted is not None and hosted.session is session:
            self._unhost(hosted, "unadvertised by its WebSocket provider")

    def service_response(self, session: Any, service: str, call_id: Any, values: Any, ok: bool) -> None:
        """Pass a client's answer to the waiting ROS caller."""
        hosted = self.hosted.get(service)
        if hosted is None or hosted.session is not session:
            raise BridgeError("service_response: %s is not advertised by this client" % service)
        if not hosted.answer(call_id, ok, values):
            raise BridgeError("service_response: no pending call %r" % (call_id,), "warning")

    def release(self, session: Any) -> None:
        """Unhost every service of a gone client (or of every client when session is None)."""
        for hosted in list(self.hosted.values()):
            if session is None or hosted.session is session:
                self._unhost(hosted, "its WebSocket provider disconnected" if session else "bridge shutting down")

    def shutdown(self) -> None:
        """Unhost everything and stop the pool (node exit)."""
        self.release(None)
        self.pool.shutdown(wait=False)
