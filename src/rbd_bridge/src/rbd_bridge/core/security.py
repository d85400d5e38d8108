"""Allow-lists (glob patterns; the RoboDog default moves nothing, DESIGN §5.4) and rosauth MACs. ROS-free."""

import fnmatch
import functools
import hashlib
import hmac
import math
from typing import Any, Callable, Dict

__all__ = ["AuthError", "Policy", "parse_glob_list", "check_mac", "make_mac", "policy_from_params"]

ROBODOG_PUBLISH = ("/rbd_gestrec/gesture", "/rbd_local/heartbeat")
ROBODOG_SUBSCRIBE = (
    "/rbd_controller/state",
    "/rbd_controller/path_queue",
    "/rbd_controller/controller_state",
    "/rbd_pos_controller/status",
    "/rbd_lidar/state",
)
ROBODOG_SERVICES = ("/rbd_controller/em_stop", "/rosapi/*")
ROBODOG_PARAMS = ()


class AuthError(ValueError):
    """An ``auth`` op that does not authenticate the client."""


def parse_glob_list(text: Any) -> Any:
    """Parse a rosbridge-style glob list (``"[*]"``, ``"['/a', '/b/*']"``, ``"[/a, /b]"``, ``"/a /b"``, a list).

    Returns:
        tuple: The globs (``()`` for an empty list), or ``None`` for ``None`` / ``""`` (not given).
    """
    if text is None:
        return None
    if isinstance(text, (list, tuple)):
        items = [str(t) for t in text]
    else:
        text = str(text).strip()
        if text == "":
            return None
        if text.startswith("[") and text.endswith("]"):
            text = text[1:-1]
        items = text.replace(",", " ").split()
    return tuple(i for i in (item.strip().strip("'\"").strip() for item in items) if i)


def _matcher(globs: Any) -> Callable[[str], bool]:
    """``(name) -> bool`` for a glob list (None or ``*`` in it: everything); answers cached (4096 names)."""
    if globs is None or "*" in globs:
        return lambda name: True
    return functools.lru_cache(maxsize=4096)(lambda name: any(fnmatch.fnmatchcase(name, p) for p in globs))


class Policy:
    """What a client may do.

    ``may_publish`` (into ROS), ``may_subscribe``, ``may_call`` (call or advertise a service;
    rosapi's are ``/rosapi/*``) and ``may_read_param`` (rosapi) are ``(name) -> bool``. A glob
    list of ``None`` (or one holding ``*``) allows everything.

    Args:
        publish_globs: Topics a client may advertise/publish.
        subscribe_globs: Topics a client may subscribe to.
        service_globs: Services a client may call or advertise.
        param_globs: Parameters rosapi may read (and write when params_writable).
        params_writable: Allow rosapi set_param / delete_param within param_globs.
        secret: Shared secret; when set, clients must ``auth`` first.
    """

    def __init__(
        self,
        publish_globs: Any = ROBODOG_PUBLISH,
        subscribe_globs: Any = ROBODOG_SUBSCRIBE,
        service_globs: Any = ROBODOG_SERVICES,
        param_globs: Any = ROBODOG_PARAMS,
        params_writable: bool = False,
        secret: str = None,
    ) -> None:
        self.publish_globs, self.may_publish = publish_globs, _matcher(publish_globs)
        self.subscribe_globs, self.may_subscribe = subscribe_globs, _matcher(subscribe_globs)
        self.service_globs, self.may_call = service_globs, _matcher(service_globs)
        self.param_globs, self.may_read_param = param_globs, _matcher(param_globs)
        self.params_writable = params_writable
        self.secret = secret
        self.authenticate = bool(secret)  # clients must auth first

    def may_see_topic(self, topic: str) -> bool:
        """Return True if rosapi may list topic (allowed in either direction)."""
        return self.may_publish(topic) or self.may_subscribe(topic)

    def may_write_param(self, name: str) -> bool:
        """Return True if rosapi may set or delete parameter name."""
        return bool(self.params_writable) and self.may_read_param(name)


def _secs(value: Any, field: str) -> Any:
    if isinstance(value, dict):
        value = value.get("secs", value.get("sec"))
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise AuthError("auth: %s must be a time" % field)
    return int(value)


def make_mac(secret: str, client: str, dest: str, rand: str, t: Any, level: str, end: Any) -> str:
    """The rosauth MAC: sha512 hex of secret + client + dest + rand + t (s) + level + end (s)."""
    text = "%s%s%s%s%d%s%d" % (secret, client, dest, rand, int(t), level, int(end))
    return hashlib.sha512(text.encode("utf-8")).hexdigest()


def check_mac(secret: str, frame: Dict[str, Any], now: Callable[..., Any], max_skew: float = 5.0) -> None:
    """Validate an ``auth`` op as rosauth's ros_mac_authentication does (now: wall clock [s]).

    Raises:
        AuthError: A field is missing, t is more than max_skew from now, end has passed, or the MAC differs.
    """
    for key in ("mac", "client", "dest", "rand", "level"):
        if not isinstance(frame.get(key), str):
            raise AuthError("auth: field %r must be a string" % key)
    t = _secs(frame.get("t"), "t")
    end = _secs(frame.get("end"), "end")
    if abs(t - now) > max_skew:
        raise AuthError("auth: request time is more than %.0f s away from the server clock" % max_skew)
    if end <= now:
        raise AuthError("auth: session end time has passed")
    expected = make_mac(secret, frame["client"], frame["dest"], frame["rand"], t, frame["level"], end)
    if not hmac.compare_digest(expected, frame["mac"].lower()):
        raise AuthError("auth: MAC does not match")


def policy_from_params(get: Callable[..., Any], secret: str = None) -> Any:
    """Build the Policy from node parameters (rosbridge names plus RoboDog extensions).

    ``topics_glob`` (rosbridge) sets both directions; ``publish_topics_glob`` /
    ``subscribe_topics_glob`` override one direction. A list not given at all keeps the
    RoboDog default; ``"[*]"`` opens it; ``"[]"`` closes it. As rosbridge does, a given
    non-empty ``services_glob`` gets ``/rosapi/*`` added, and a given ``params_glob`` is
    writable unless ``params_writable`` is false (the RoboDog default has no parameters).
    ``get(name, default)`` reads a private parameter.
    """
    topics = parse_glob_list(get("topics_glob", None))
    publish = parse_glob_list(get("publish_topics_glob", None))
    subscribe = parse_glob_list(get("subscribe_topics_glob", None))
    services = parse_glob_list(get("services_glob", None))
    params = parse_glob_list(get("params_glob", None))
    if publish is None:
        publish = topics if topics is not None else ROBODOG_PUBLISH
    if subscribe is None:
        subscribe = topics if topics is not None else ROBODOG_SUBSCRIBE
    if services is None:
        services = ROBODOG_SERVICES
    elif services and "/rosapi/*" not in services:
        services = services + ("/rosapi/*",)  # as rosbridge: rosapi stays reachable
    writable = get("params_writable", None)
    if writable is None or writable == "":
        writable = params is not None  # as rosbridge: a given params_glob is readable and writable
    elif isinstance(writable, str):
        writable = writable.strip().lower() in ("true", "1", "yes")
    if params is None:
        params = ROBODOG_PARAMS
    return Policy(publish, subscribe, services, params, params_writable=bool(writable), secret=secret)
