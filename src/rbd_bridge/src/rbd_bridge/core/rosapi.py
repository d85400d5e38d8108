"""rosapi services served in-process by the bridge (rosapi is not in Debian).

Clients call ``/rosapi/<name>`` with ``call_service`` exactly as with rosbridge_suite's
rosapi node; request and response field names are rosapi's (ROS 1). The services are not
registered with the ROS master: only WebSocket clients can reach them. Results are
filtered through the bridge's allow-lists. Parameter values travel as JSON strings.

ROS-free: ``RosApi`` needs a *graph* object with rosgraph.Master's XML-RPC methods
(``getTopicTypes``, ``getSystemState``, ``lookupService``), a *params* object with
``get(name)``, ``set(name, value)``, ``has(name)``, ``delete(name)``, ``search(name)``,
``names()``, and a *types* object with ``typedefs(type_name, part)`` (rosapi ``TypeDef``
dicts of a message, or of a service's ``"request"``/``"response"``) and
``full_text(type_name)``, both raising ``ConversionError``; the node passes ROS-backed
ones (:mod:`rbd_bridge.ros.graph`), tests may pass fakes.
"""

import json
from typing import Any, Callable

from rbd_bridge.core.types import ConversionError

__all__ = ["RosApi", "ROSAPI_TYPES", "RosApiError"]

ROSAPI_TYPES = {
    "topics": "rosapi/Topics",
    "topic_type": "rosapi/TopicType",
    "topics_for_type": "rosapi/TopicsForType",
    "topics_and_raw_types": "rosapi/TopicsAndRawTypes",
    "services": "rosapi/Services",
    "service_type": "rosapi/ServiceType",
    "services_for_type": "rosapi/ServicesForType",
    "service_providers": "rosapi/ServiceProviders",
    "service_node": "rosapi/ServiceNode",
    "service_host": "rosapi/ServiceHost",
    "nodes": "rosapi/Nodes",
    "node_details": "rosapi/NodeDetails",
    "publishers": "rosapi/Publishers",
    "subscribers": "rosapi/Subscribers",
    "message_details": "rosapi/MessageDetails",
    "service_request_details": "rosapi/ServiceRequestDetails",
    "service_response_details": "rosapi/ServiceResponseDetails",
    "get_param": "rosapi/GetParam",
    "set_param": "rosapi/SetParam",
    "has_param": "rosapi/HasParam",
    "delete_param": "rosapi/DeleteParam",
    "search_param": "rosapi/SearchParam",
    "get_param_names": "rosapi/GetParamNames",
    "get_time": "rosapi/GetTime",
    "action_servers": "rosapi/GetActionServers",
}

_ACTION_SUFFIXES = ("/goal", "/cancel", "/status", "/feedback", "/result")


class RosApiError(Exception):
    """A rosapi request that fails (sent back as ``result: false``)."""


def _str_arg(args: Any, key: str, default: Any = "") -> Any:
    value = args.get(key, default)
    if value is None:
        return default
    if not isinstance(value, str):
        raise RosApiError("rosapi: %r must be a string" % key)
    return value


class RosApi:
    """Dispatch ``/rosapi/*`` calls.

    Args:
        policy: The bridge's :class:`rbd_bridge.security.Policy`.
        graph: rosgraph.Master-like object.
        params: Parameter store adapter (see module doc).
        now: Callable returning (secs, nsecs) of ROS time.
        service_type: Callable(service) -> type name of a ROS service (may raise).
        types: Message definitions adapter (see module doc).
    """

    def __init__(
        self, policy: Any, graph: Any, params: Any, now: Callable[..., Any], service_type: Any, types: Any = None
    ) -> None:
        """Keep the adapters."""
        self.policy = policy
        self.graph = graph
        self.params = params
        self.types = types
        self.now = now
        self.lookup_service_type = service_type

    @staticmethod
    def handles(service: str) -> Any:
        """Return True if service is one of ours."""
        return service.startswith("/rosapi/") and service[len("/rosapi/") :] in ROSAPI_TYPES

    def call(self, service: str, args: Any) -> Any:
        """Serve one call.

        Args:
            service: ``/rosapi/<name>``.
            args: Request dict (rosapi field names); a list is mapped by position.

        Returns:
            dict: Response fields.

        Raises:
            RosApiError: On a bad request or a denied name.
        """
        name = service[len("/rosapi/") :]
        if isinstance(args, list):
            args = self._positional(name, args)
        elif args is None:
            args = {}
        return getattr(self, "_" + name)(args)

    def _positional(self, name: str, args: Any) -> Any:
        order = {
            "topic_type": ["topic"],
            "topics_for_type": ["type"],
            "service_type": ["service"],
            "services_for_type": ["type"],
            "service_providers": ["service"],
            "service_node": ["service"],
            "service_host": ["service"],
            "node_details": ["node"],
            "publishers": ["topic"],
            "subscribers": ["topic"],
            "message_details": ["type"],
            "service_request_details": ["type"],
            "service_response_details": ["type"],
            "get_param": ["name", "default"],
            "set_param": ["name", "value"],
            "has_param": ["name"],
            "delete_param": ["name"],
            "search_param": ["name"],
        }.get(name, [])
        if len(args) > len(order):
            raise RosApiError("rosapi/%s: too many arguments" % name)
        return dict(zip(order, args))

    # ------------------------------------------------------------ graph helpers

    def _topic_types(self) -> Any:
        # as rosapi: the master's topic types keep topics whose publishers are all gone, so
        # only topics that have a publisher or subscriber now count (unknown type: "")
        pubs, subs, _ = self._state()
        live = set(t for t, nodes in pubs + subs if nodes and self.policy.may_see_topic(t))
        types = dict((t, ty) for t, ty in self.graph.getTopicTypes() if t in live)
        return [(t, types.get(t, "")) for t in live]

    def _state(self) -> Any:
        return self.graph.getSystemState()

    def _ros_services(self) -> Any:
        return sorted(s for s, _ in self._state()[2] if self.policy.may_call(s))

    def _own_services(self) -> Any:
        return sorted("/rosapi/" + n for n in ROSAPI_TYPES if self.policy.may_call("/rosapi/" + n))

    def _service_type_of(self, service: str) -> Any:
        if self.handles(service):
            return ROSAPI_TYPES[service[len("/rosapi/") :]]
        if not self.policy.may_call(service):
            return ""
        try:
            return self.lookup_service_type(service) or ""
        except Exception:
            return ""

    # ------------------------------------------------------------ topics

    def _topics(self, args: Any) -> Any:
        pairs = sorted(self._topic_types())
        return {"topics": [t for t, _ in pairs], "types": [ty for _, ty in pairs]}

    def _topic_type(self, args: Any) -> Any:
        topic = _str_arg(args, "topic")
        for t, ty in self._topic_types():
            if t == topic:
                return {"type": ty}
        return {"type": ""}

    def _topics_for_type(self, args: Any) -> Any:
        wanted = _str_arg(args, "type")
        return {"topics": sorted(t for t, ty in self._topic_types() if ty == wanted)}

    def _topics_and_raw_types(self, args: Any) -> Any:
        pairs = sorted(self._topic_types())
        texts = []
        for _, ty in pairs:
            try:
                texts.append(self.types.full_text(ty))
            except ConversionError:
                texts.append("")
        return {"topics": [t for t, _ in pairs], "types": [ty for _, ty in pairs], "typedefs_full_text": texts}

    def _publishers(self, args: Any) -> Any:
        topic = _str_arg(args, "topic")
        if not self.policy.may_see_topic(topic):
            return {"publishers": []}
        for t, nodes in self._state()[0]:
            if t == topic:
                return {"publishers": sorted(nodes)}
        return {"publishers": []}

    def _subscribers(self, args: Any) -> Any:
        topic = _str_arg(args, "topic")
        if not self.policy.may_see_topic(topic):
            return {"subscribers": []}
        for t, nodes in self._state()[1]:
            if t == topic:
                return {"subscribers": sorted(nodes)}
        return {"subscribers": []}

    # ------------------------------------------------------------ services

    def _services(self, args: Any) -> Any:
        return {"services": sorted(set(self._ros_services()) | set(self._own_services()))}

    def _service_type(self, args: Any) -> Any:
        return {"type": self._service_type_of(_str_arg(args, "service"))}

    def _services_for_type(self, args: Any) -> Any:
        wanted = _str_arg(args, "type")
        names = self._ros_services() + self._own_services()
        return {"services": sorted(s for s in names if self._service_type_of(s) == wanted)}

    def _providers(self, service: str) -> Any:
        if not self.policy.may_call(service):
            return []
        for s, nodes in self._state()[2]:
            if s == service:
                return sorted(nodes)
        return []

    def _service_providers(self, args: Any) -> Any:
        return {"providers": self._providers(_str_arg(args, "service"))}

    def _service_node(self, args: Any) -> Any:
        nodes = self._providers(_str_arg(args, "service"))
        return {"node": nodes[0] if nodes else ""}

    def _service_host(self, args: Any) -> Any:
        service = _str_arg(args, "service")
        if not self.policy.may_call(service):
            return {"host": ""}
        try:
            uri = self.graph.lookupService(service)
        except Exception:
            return {"host": ""}
        host = uri.split("//", 1)[-1].split(":", 1)[0] if isinstance(uri, str) else ""
        return {"host": host}

    # ------------------------------------------------------------ nodes

    def _nodes(self, args: Any) -> Any:
        names = set()
        for group in self._state():
            for _, nodes in group:
                names.update(nodes)
        return {"nodes": sorted(names)}

    def _node_details(self, args: Any) -> Any:
        node = _str_arg(args, "node")
        pubs, subs, srvs = self._state()
        return {
            "subscribing": sorted(t for t, n in subs if node in n and self.policy.may_see_topic(t)),
            "publishing": sorted(t for t, n in pubs if node in n and self.policy.may_see_topic(t)),
            "services": sorted(s for s, n in srvs if node in n and self.policy.may_call(s)),
        }

    def _action_servers(self, args: Any) -> Any:
        # as rosapi (ROS 1): a namespace (not the root) with all five actionlib topics
        topics = set(t for t, _ in self._topic_types())
        bases = set()
        for t in topics:
            if t.endswith("/goal"):
                base = t[: -len("/goal")]
                if base and all(base + s in topics for s in _ACTION_SUFFIXES):
                    bases.add(base)
        return {"action_servers": sorted(bases)}

    # ------------------------------------------------------------ types

    def _details(self, args: Any, part: str = "") -> Any:
        try:
            return {"typedefs": self.types.typedefs(_str_arg(args, "type"), part)}
        except ConversionError as exc:
            raise RosApiError(str(exc)) from None

    def _message_details(self, args: Any) -> Any:
        return self._details(args)

    def _service_request_details(self, args: Any) -> Any:
        return self._details(args, "request")

    def _service_response_details(self, args: Any) -> Any:
        return self._details(args, "response")

    # ------------------------------------------------------------ params

    def _param_name(self, args: Any, write: bool = False) -> Any:
        name = _str_arg(args, "name")
        if not name:
            raise RosApiError("rosapi: parameter name missing")
        if not name.startswith("/"):
            name = "/" + name
        if not self.policy.may_read_param(name):
            raise RosApiError("parameter %s is not allowed by this bridge's allow-list" % name)
        if write and not self.policy.may_write_param(name):
            raise RosApiError("parameter %s is read-only through this bridge" % name)
        return name

    def _get_param(self, args: Any) -> Any:
        name = self._param_name(args)
        default = args.get("default", args.get("default_value", ""))
        if self.params.has(name):
            return {"value": json.dumps(self.params.get(name))}
        if isinstance(default, str) and default:
            try:
                return {"value": json.dumps(json.loads(default))}
            except ValueError:
                return {"value": json.dumps(default)}
        return {"value": "null"}

    def _set_param(self, args: Any) -> Any:
        name = self._param_name(args, write=True)
        text = _str_arg(args, "value")
        try:
            value = json.loads(text)
        except ValueError:
            value = text
        self.params.set(name, value)
        return {}

    def _has_param(self, args: Any) -> Any:
        name = self._param_name(args)
        return {"exists": bool(self.params.has(name))}

    def _delete_param(self, args: Any) -> Any:
        name = self._param_name(args, write=True)
        if self.params.has(name):
            self.params.delete(name)
        return {}

    def _search_param(self, args: Any) -> Any:
        name = _str_arg(args, "name")
        found = self.params.search(name) or ""
        if found and not self.policy.may_read_param(found):
            found = ""
        return {"global_name": found}

    def _get_param_names(self, args: Any) -> Any:
        return {"names": sorted(n for n in self.params.names() if self.policy.may_read_param(n))}

    def _get_time(self, args: Any) -> Any:
        secs, nsecs = self.now()
        return {"time": {"secs": secs, "nsecs": nsecs}}
