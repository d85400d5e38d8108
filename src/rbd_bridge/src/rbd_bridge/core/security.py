"""Allow-lists (glob patterns; the RoboDog default moves nothing, DESIGN §5.4) and rosauth MACs. ROS-free."""

import fnmatch
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


class _Globs:
    """A glob list (None = everything) whose answers are cached (at most 4096 names)."""

    def __init__(self, globs: Any) -> None:
        self.globs = globs
        self.cache = {}

    def __call__(self, name: str) -> bool:
        hit = self.cache.get(name)
        if hit is None:
            hit = self.globs is None or any(fnmatch.fnmatchcase(name, p) for p in self.globs)
            if len(self.cache) >= 4096:
                self.cache.clear()
            self.cache[name] = hit
        return hit


class Policy:
    """What a client may do.

    ``may_publish`` (into ROS), ``may_subscribe``, ``may_call`` (call or advertise a service;
    rosapi's are ``/rosapi/*``) and ``may_read_param`` (rosapi) are ``(name) -> bool``. A glob
    list of ``None`` allows everything.

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
        self.publish_globs, self.may_publish = publish_globs, _Globs(publish_globs)
        self.subscribe_globs, self.may_subscribe = subscribe_globs, _Globs(subscribe_globs)
        self.service_globs, self.may_call = service_globs, _Globs(service_globs)
        self.param_globs, self.may_read_param = param_globs, _Globs(param_globs)
        self.params_writable = params_writable
        self.secret = secret

    @property
    def authenticate(self) -> bool:
        """True when clients must authenticate."""
        return bool(self.secret)

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
    fields = {}
    for key in ("mac", "client", "dest", "rand", "level"):
        value = frame.get(key)
        if not isinstance(value, str):
            raise AuthError("auth: field %r must be a string" % key)
        fields[key] = value
    t = _secs(frame.get("t"), "t")
    end = _secs(frame.get("end"), "end")
    if abs(t - now) > max_skew:
        raise AuthError("auth: request time is more than %.0f s away from the server clock" % max_skew)
    if end <= now:
        raise AuthError("auth: session end time has passed")
    expected = make_mac(secret, fields["client"], fields["dest"], fields["rand"], t, fields["level"], end)
    if not hmac.compare_digest(expected, fields["mac"].lower()):
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
    return Policy(
        publish_globs=None if publish == ("*",) else publish,
        subscribe_globs=None if subscribe == ("*",) else subscribe,
        service_globs=None if "*" in services else services,
        param_globs=None if params == ("*",) else params,
        params_writable=bool(writable),
        secret=secret,
    )
