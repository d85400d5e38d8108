"""rosapi.RosApi against fake graph and parameter adapters (no ROS master needed)."""

import json

import pytest

from rbd_bridge.core.rosapi import RosApi, RosApiError
from rbd_bridge.core.security import Policy

ACTION = ["/goal", "/cancel", "/status", "/feedback", "/result"]


class FakeGraph:
    """rosgraph.Master-like: topic types and a system state, as the master returns them."""

    def __init__(self, topic_types=(), pubs=(), subs=(), srvs=()):
        self.topic_types = [list(p) for p in topic_types]
        self.state = [[list(p) for p in pubs], [list(p) for p in subs], [list(p) for p in srvs]]

    def getTopicTypes(self):  # noqa: N802 (the master's method name)
        return self.topic_types

    def getSystemState(self):  # noqa: N802
        return self.state

    def lookupService(self, name):  # noqa: N802
        raise KeyError(name)


class FakeParams:
    """A parameter server: a flat dict of global names; search walks up from /ns/node."""

    def __init__(self, values=None, namespace="/ns/node"):
        self.values = dict(values or {})
        self.namespace = namespace
        self.searched = []

    def get(self, name):
        return self.values[name]

    def set(self, name, value):
        self.values[name] = value

    def has(self, name):
        return name in self.values

    def delete(self, name):
        del self.values[name]

    def search(self, name):
        self.searched.append(name)
        parts = self.namespace.strip("/").split("/")[:-1]
        while True:
            candidate = "/" + "/".join(parts + [name.lstrip("/")])
            if candidate in self.values:
                return candidate
            if not parts:
                return None
            parts.pop()

    def names(self):
        return list(self.values)


def make_api(graph=None, params=None, **policy):
    policy.setdefault("publish_globs", None)
    policy.setdefault("subscribe_globs", None)
    policy.setdefault("service_globs", None)
    policy.setdefault("param_globs", None)
    policy.setdefault("params_writable", True)
    return RosApi(Policy(**policy), graph or FakeGraph(), params or FakeParams(), lambda: (5, 6), lambda s: "")


def test_subscribers_lists_the_nodes_of_one_topic_and_respects_the_allow_list():
    graph = FakeGraph(
        pubs=[("/a", ["/talker"])],
        subs=[("/a", ["/z_listener", "/b_listener"]), ("/secret", ["/spy"])],
    )
    api = make_api(graph, subscribe_globs=["/a"], publish_globs=[])
    assert api.call("/rosapi/subscribers", {"topic": "/a"}) == {"subscribers": ["/b_listener", "/z_listener"]}
    assert api.call("/rosapi/subscribers", ["/a"]) == {"subscribers": ["/b_listener", "/z_listener"]}
    assert api.call("/rosapi/subscribers", {"topic": "/nobody"}) == {"subscribers": []}
    # a topic outside the allow-list is invisible, even though it has subscribers
    assert api.call("/rosapi/subscribers", {"topic": "/secret"}) == {"subscribers": []}
    # publishers and subscribers are not mixed up
    assert api.call("/rosapi/publishers", {"topic": "/a"}) == {"publishers": ["/talker"]}
    with pytest.raises(RosApiError):
        api.call("/rosapi/subscribers", {"topic": 5})


def test_search_param_walks_up_the_namespaces_and_hides_denied_names():
    params = FakeParams({"/ns/gain": 1, "/gain": 2, "/top": 3, "/private/key": "x"})
    api = make_api(params=params, param_globs=["/ns/*", "/top"])
    assert api.call("/rosapi/search_param", {"name": "gain"}) == {"global_name": "/ns/gain"}
    assert api.call("/rosapi/search_param", ["top"]) == {"global_name": "/top"}
    assert api.call("/rosapi/search_param", {"name": "missing"}) == {"global_name": ""}
    # found by the parameter server but outside the allow-list: not revealed
    assert api.call("/rosapi/search_param", {"name": "private/key"}) == {"global_name": ""}
    assert params.searched == ["gain", "top", "missing", "private/key"]


def test_action_servers_need_all_five_topics():
    complete = ["/dock" + s for s in ACTION] + ["/arm/move" + s for s in ACTION]
    incomplete = ["/half" + s for s in ("/goal", "/cancel", "/status")]  # a server also has feedback/result
    no_status = ["/nostatus" + s for s in ("/goal", "/cancel", "/feedback", "/result")]
    at_root = list(ACTION)  # "/goal" etc. have no action namespace
    topics = complete + incomplete + no_status + at_root + ["/dock_extra/goal", "/chatter"]
    graph = FakeGraph(topic_types=[(t, "some_msgs/Thing") for t in topics], pubs=[(t, ["/n"]) for t in topics])
    assert make_api(graph).call("/rosapi/action_servers", {}) == {"action_servers": ["/arm/move", "/dock"]}
    # only topics the allow-list shows count
    hidden = make_api(graph, publish_globs=["/dock/*"], subscribe_globs=["/arm/*"])
    assert hidden.call("/rosapi/action_servers", {}) == {"action_servers": ["/arm/move", "/dock"]}
    partly = make_api(graph, publish_globs=["/dock/goal", "/dock/cancel", "/dock/status"], subscribe_globs=[])
    assert partly.call("/rosapi/action_servers", {}) == {"action_servers": []}
    assert make_api(FakeGraph()).call("/rosapi/action_servers", None) == {"action_servers": []}


def test_topics_are_those_with_a_publisher_or_subscriber_now():
    # rosapi (ROS 1) compares the master's topic types with getSystemState: a topic whose
    # last publisher and subscriber are gone keeps its type in the master but is not listed;
    # a live topic whose type the master does not know is listed with type ""
    graph = FakeGraph(
        topic_types=[("/gone", "std_msgs/String"), ("/pub", "std_msgs/Int32"), ("/sub", "std_msgs/Bool")],
        pubs=[("/pub", ["/talker"]), ("/gone", [])],
        subs=[("/sub", ["/listener"]), ("/untyped", ["/listener"])],
    )
    assert make_api(graph).call("/rosapi/topics", {}) == {
        "topics": ["/pub", "/sub", "/untyped"],
        "types": ["std_msgs/Int32", "std_msgs/Bool", ""],
    }
    assert make_api(graph).call("/rosapi/topic_type", {"topic": "/gone"}) == {"type": ""}
    assert make_api(graph, subscribe_globs=["/sub"], publish_globs=[]).call("/rosapi/topics", {}) == {
        "topics": ["/sub"],
        "types": ["std_msgs/Bool"],
    }


def test_get_param_returns_json_and_handles_defaults():
    params = FakeParams({"/robot/speed": 0.5, "/robot/name": "a1", "/robot/list": [1, {"k": None}]})
    api = make_api(params=params)
    assert api.call("/rosapi/get_param", {"name": "/robot/speed"}) == {"value": "0.5"}
    assert api.call("/rosapi/get_param", {"name": "robot/name"}) == {"value": '"a1"'}  # made global
    assert json.loads(api.call("/rosapi/get_param", ["/robot/list"])["value"]) == [1, {"k": None}]
    # an existing value wins over the default
    assert api.call("/rosapi/get_param", {"name": "/robot/speed", "default": "7"}) == {"value": "0.5"}
    # missing: the default (a JSON text) is returned as JSON; a non-JSON default as a JSON string
    assert api.call("/rosapi/get_param", {"name": "/nope", "default": "[1, 2]"}) == {"value": "[1, 2]"}
    assert api.call("/rosapi/get_param", ["/nope", "plain text"]) == {"value": '"plain text"'}
    assert api.call("/rosapi/get_param", {"name": "/nope", "default_value": "3"}) == {"value": "3"}
    # missing without a default (or an empty one): null
    assert api.call("/rosapi/get_param", {"name": "/nope"}) == {"value": "null"}
    assert api.call("/rosapi/get_param", {"name": "/nope", "default": ""}) == {"value": "null"}
    with pytest.raises(RosApiError, match="name missing"):
        api.call("/rosapi/get_param", {"default": "1"})
    with pytest.raises(RosApiError, match="too many"):
        api.call("/rosapi/get_param", ["/a", "1", "extra"])


def test_params_glob_filters_reads_writes_and_names():
    params = FakeParams({"/robot/speed": 0.5, "/robot/secret": "s3", "/other": 1})
    api = make_api(params=params, param_globs=["/robot/speed", "/robot/limits/*"], params_writable=False)
    assert api.call("/rosapi/get_param_names", {}) == {"names": ["/robot/speed"]}
    assert api.call("/rosapi/get_param", {"name": "/robot/speed"}) == {"value": "0.5"}
    for name in ("/robot/secret", "/other"):
        with pytest.raises(RosApiError, match="allow-list"):
            api.call("/rosapi/get_param", {"name": name})
        with pytest.raises(RosApiError, match="allow-list"):
            api.call("/rosapi/has_param", {"name": name})
    # readable but not writable: nothing changes in the store
    with pytest.raises(RosApiError, match="read-only"):
        api.call("/rosapi/set_param", {"name": "/robot/speed", "value": "9"})
    with pytest.raises(RosApiError, match="read-only"):
        api.call("/rosapi/delete_param", {"name": "/robot/speed"})
    assert params.values == {"/robot/speed": 0.5, "/robot/secret": "s3", "/other": 1}

    writable = make_api(params=params, param_globs=["/robot/limits/*"], params_writable=True)
    assert writable.call("/rosapi/set_param", {"name": "/robot/limits/v", "value": "[1.5, 2]"}) == {}
    assert writable.call("/rosapi/set_param", ["/robot/limits/label", "not json"]) == {}
    assert params.values["/robot/limits/v"] == [1.5, 2] and params.values["/robot/limits/label"] == "not json"
    with pytest.raises(RosApiError, match="allow-list"):
        writable.call("/rosapi/set_param", {"name": "/robot/secret", "value": "1"})
    assert writable.call("/rosapi/delete_param", {"name": "/robot/limits/v"}) == {}
    assert "/robot/limits/v" not in params.values and params.values["/robot/secret"] == "s3"
    assert writable.call("/rosapi/get_param_names", {}) == {"names": ["/robot/limits/label"]}
