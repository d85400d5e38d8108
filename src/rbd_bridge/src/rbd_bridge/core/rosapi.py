"""rosapi (ROS 1) services served in-process for WebSocket clients only, filtered by the allow-lists. ROS-free.

Needs a *graph* with rosgraph.Master's ``getTopicTypes``, ``getSystemState`` and
``lookupService``; *params* with ``get``, ``set``, ``has``, ``delete``, ``search``
(by name) and ``names()``; *types* with ``typedefs(type_name, part)`` and
``full_text(type_name)``, raising ``ConversionError`` (:mod:`rbd_bridge.ros.graph`, or fakes).
"""

import json
from typing import Any, Callable, Dict

from rbd_bridge.core.types import ConversionError

__all__ = ["RosApi", "ROSAPI_TYPES", "RosApiError"]

_ACTION_SUFFIXES = ("/goal", "/cancel", "/status", "/feedback", "/result")


class RosApiError(Exception):
    """A rosapi request that fails (sent back as ``result: false``)."""


def _str_arg(args: Dict[str, Any], key: str) -> str:
    value = args.get(key)
    if value is None:
        return ""
    if not isinstance(value, str):
        raise RosApiError("rosapi: %r must be a string" % key)
    return value


def _loads(text: str) -> Any:
    """JSON text as its value, any other text as itself (parameter values, as rosapi)."""
    try:
        return json.loads(text)
    except ValueError:
        return text


class RosApi:
    """Dispatch ``/rosapi/*`` calls.

    Args:
        policy: The bridge's :class:`rbd_bridge.core.security.Policy`.
        graph: rosgraph.Master-like object.
        params: Parameter store adapter (module doc).
        now: Callable returning (secs, nsecs) of ROS time.
        service_type: Callable(service) -> type name of a ROS service (may raise).
        types: Message definitions adapter (module doc).
    """

    def __init__(
        self, policy: Any, graph: Any, params: Any, now: Callable[..., Any], service_type: Any, types: Any = None
    ) -> None:
        self.policy = policy
        self.graph = graph
        self.params = params
        self.types = types
        self.now = now
        self.lookup_service_type = service_type

    @staticmethod
    def handles(service: str) -> bool:
        """Return True if service is one of ours."""
        return service.startswith("/rosapi/") and service[8:] in _SERVICES

    def call(self, service: str, args: Any) -> Dict[str, Any]:
        """Serve one call of ``/rosapi/<name>`` with a request dict (a list is mapped by position).

        Raises:
            RosApiError: On a bad request or a denied name.
        """
        name = service[8:]
        order, handler = _SERVICES[name]
        if isinstance(args, list):
            if len(args) > len(order):
                raise RosApiError("rosapi/%s: too many arguments" % name)
            args = dict(zip(order, args))
        return handler(self, args or {})

    def _topic_types(self) -> Any:
        # as rosapi: the master's topic types keep topics whose publishers are all gone, so
        # only topics with a publisher or subscriber now count (unknown type: "")
        pubs, subs, _ = self.graph.getSystemState()
        live = set(t for t, nodes in pubs + subs if nodes and self.policy.may_see_topic(t))
        types = dict((t, ty) for t, ty in self.graph.getTopicTypes() if t in live)
        return sorted((t, types.get(t, "")) for t in live)

    def _service_names(self) -> Any:
        names = set(s for s, _ in self.graph.getSystemState()[2]) | set("/rosapi/" + n for n in _SERVICES)
        return sorted(s for s in names if self.policy.may_call(s))

    def _service_type_of(self, service: str) -> str:
        if self.handles(service):
            return ROSAPI_TYPES[service[8:]]
        try:
            return (self.policy.may_call(service) and self.lookup_service_type(service)) or ""
        except Exception:
            return ""

    def _services_for_type(self, args: Any) -> Any:
        wanted = _str_arg(args, "type")
        return {"services": [s for s in self._service_names() if self._service_type_of(s) == wanted]}

    def _on(self, args: Any, part: int) -> Any:
        """Nodes publishing (part 0), subscribing (1) to an allowed topic or providing (2) an allowed service."""
        name = _str_arg(args, "service" if part == 2 else "topic")
        allowed = self.policy.may_call if part == 2 else self.policy.may_see_topic
        state = self.graph.getSystemState()[part] if allowed(name) else []
        return next((sorted(nodes) for n, nodes in state if n == name), [])

    def _topics(self, args: Any) -> Any:
        pairs = self._topic_types()
        return {"topics": [t for t, _ in pairs], "types": [ty for _, ty in pairs]}

    def _topics_and_raw_types(self, args: Any) -> Any:
        reply = self._topics(args)
        texts = []
        for type_name in reply["types"]:
            try:
                texts.append(self.types.full_text(type_name))
            except ConversionError:
                texts.append("")
        reply["typedefs_full_text"] = texts
        return reply

    def _service_host(self, args: Any) -> Any:
        service = _str_arg(args, "service")
        try:
            uri = self.graph.lookupService(service) if self.policy.may_call(service) else ""
        except Exception:
            uri = ""
        return {"host": uri.split("//", 1)[-1].split(":", 1)[0] if isinstance(uri, str) and uri else ""}

    def _nodes(self, args: Any) -> Any:
        return {"nodes": sorted(set(n for part in self.graph.getSystemState() for _, nodes in part for n in nodes))}

    def _node_details(self, args: Any) -> Any:
        node = _str_arg(args, "node")
        pubs, subs, srvs = self.graph.getSystemState()
        see, call = self.policy.may_see_topic, self.policy.may_call
        return {
            "subscribing": sorted(t for t, n in subs if node in n and see(t)),
            "publishing": sorted(t for t, n in pubs if node in n and see(t)),
            "services": sorted(s for s, n in srvs if node in n and call(s)),
        }

    def _action_servers(self, args: Any) -> Any:
        # as rosapi (ROS 1): a namespace (not the root) with all five actionlib topics
        topics = set(t for t, _ in self._topic_types())
        bases = set(t[:-5] for t in topics if t.endswith("/goal") and len(t) > 5)
        return {"action_servers": sorted(b for b in bases if all(b + s in topics for s in _ACTION_SUFFIXES))}

    def _details(self, args: Any, part: str) -> Any:
        try:
            return {"typedefs": self.types.typedefs(_str_arg(args, "type"), part)}
        except ConversionError as exc:
            raise RosApiError(str(exc)) from None

    def _param_name(self, args: Any, write: bool = False) -> str:
        name = _str_arg(args, "name")
        if not name:
            raise RosApiError("rosapi: parameter name missing")
        name = name if name.startswith("/") else "/" + name
        if not self.policy.may_read_param(name):
            raise RosApiError("parameter %s is not allowed by this bridge's allow-list" % name)
        if write and not self.policy.may_write_param(name):
            raise RosApiError("parameter %s is read-only through this bridge" % name)
        return name

    def _get_param(self, args: Any) -> Any:
        name = self._param_name(args)
        default = args.get("default", args.get("default_value", ""))
        if self.params.has(name):
            value = self.params.get(name)
        else:
            value = _loads(default) if isinstance(default, str) and default else None
        return {"value": json.dumps(value)}

    def _set_param(self, args: Any) -> Any:
        self.params.set(self._param_name(args, write=True), _loads(_str_arg(args, "value")))
        return {}

    def _delete_param(self, args: Any) -> Any:
        name = self._param_name(args, write=True)
        if self.params.has(name):
            self.params.delete(name)
        return {}

    def _search_param(self, args: Any) -> Any:
        found = self.params.search(_str_arg(args, "name")) or ""
        return {"global_name": found if found and self.policy.may_read_param(found) else ""}


# name: (request fields in order, for args given as a list; handler(api, args) -> response)
_SERVICES = {
    "topics": ((), RosApi._topics),
    "topic_type": (("topic",), lambda api, a: {"type": dict(api._topic_types()).get(_str_arg(a, "topic"), "")}),
    "topics_for_type": (
        ("type",),
        lambda api, a: {"topics": [t for t, ty in api._topic_types() if ty == _str_arg(a, "type")]},
    ),
    "topics_and_raw_types": ((), RosApi._topics_and_raw_types),
    "services": ((), lambda api, a: {"services": api._service_names()}),
    "service_type": (("service",), lambda api, a: {"type": api._service_type_of(_str_arg(a, "service"))}),
    "services_for_type": (("type",), RosApi._services_for_type),
    "service_providers": (("service",), lambda api, a: {"providers": api._on(a, 2)}),
    "service_node": (("service",), lambda api, a: {"node": (api._on(a, 2) or [""])[0]}),
    "service_host": (("service",), RosApi._service_host),
    "nodes": ((), RosApi._nodes),
    "node_details": (("node",), RosApi._node_details),
    "publishers": (("topic",), lambda api, a: {"publishers": api._on(a, 0)}),
    "subscribers": (("topic",), lambda api, a: {"subscribers": api._on(a, 1)}),
    "message_details": (("type",), lambda api, a: api._details(a, "")),
    "service_request_details": (("type",), lambda api, a: api._details(a, "request")),
    "service_response_details": (("type",), lambda api, a: api._details(a, "response")),
    "get_param": (("name", "default"), RosApi._get_param),
    "set_param": (("name", "value"), RosApi._set_param),
    "has_param": (("name",), lambda api, a: {"exists": bool(api.params.has(api._param_name(a)))}),
    "delete_param": (("name",), RosApi._delete_param),
    "search_param": (("name",), RosApi._search_param),
    "get_param_names": ((), lambda api, a: {"names": sorted(filter(api.policy.may_read_param, api.params.names()))}),
    "get_time": ((), lambda api, a: {"time": dict(zip(("secs", "nsecs"), api.now()))}),
    "action_servers": ((), RosApi._action_servers),
}
# rosapi's type of each: its CamelCase name
ROSAPI_TYPES = {name: "rosapi/" + name.title().replace("_", "") for name in _SERVICES}
ROSAPI_TYPES["action_servers"] = "rosapi/GetActionServers"
