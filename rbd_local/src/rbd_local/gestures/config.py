"""Configuration of the laptop app (YAML): gesture -> trick mapping, model, bridge address."""

import copy
import os

import yaml

PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_CONFIG = os.path.join(PACKAGE_DIR, "config", "default.yaml")
DEFAULT_MODEL = os.path.join(PACKAGE_DIR, "models", "gesture_model.npz")
KNOWN_KEYS = ("gestures", "model", "threshold", "min_consecutive", "cooldown_s", "model_complexity", "bridge")


def user_model_path() -> str:
    """Where taught gestures are kept when no model file is configured.

    ``$XDG_DATA_HOME/rbd_local/gesture_model.npz`` (``~/.local/share`` without XDG_DATA_HOME).
    """
    base = os.environ.get("XDG_DATA_HOME") or os.path.join(os.path.expanduser("~"), ".local", "share")
    return os.path.join(base, "rbd_local", "gesture_model.npz")


def load_config(path: str = None) -> dict:
    """Read and validate a configuration file; missing keys take the defaults.

    Args:
        path: YAML file, or None for the packaged default.

    Returns:
        The configuration dictionary. ``model`` is resolved to a path: the configured file,
        else the user's model (:func:`user_model_path`, written by teach mode) if it exists,
        else the shipped one. ``teach_model`` is where teach mode saves: the configured file,
        else the user's model.

    Raises:
        ValueError: on unknown keys or invalid values, with the offending key named.
        OSError: if the file cannot be read.
    """
    with open(DEFAULT_CONFIG) as fh:
        cfg = yaml.safe_load(fh)
    if path:
        with open(path) as fh:
            user = yaml.safe_load(fh) or {}
        if not isinstance(user, dict):
            raise ValueError("%s: top level must be a mapping" % path)
        unknown = sorted(set(user) - set(KNOWN_KEYS))
        if unknown:
            raise ValueError("%s: unknown keys %s (known: %s)" % (path, unknown, ", ".join(KNOWN_KEYS)))
        cfg = copy.deepcopy(cfg)
        for key, value in user.items():
            if key == "bridge" and isinstance(value, dict):
                cfg["bridge"].update(value)
            else:
                cfg[key] = value
    gestures = cfg.get("gestures")
    if not isinstance(gestures, dict) or not gestures:
        raise ValueError("gestures: must map gesture classes to trick commands")
    for g, cmd in gestures.items():
        if not isinstance(g, str) or not isinstance(cmd, str) or not cmd.strip():
            raise ValueError("gestures: %r -> %r must map a class name to a non-empty command" % (g, cmd))
        if g == "none":
            raise ValueError("gestures: the rejection class 'none' cannot be mapped to a command")
    thr = cfg.get("threshold")
    if thr is not None and not (isinstance(thr, (int, float)) and 0.0 < float(thr) <= 1.0):
        raise ValueError("threshold: must be empty or in (0, 1], got %r" % thr)
    if not isinstance(cfg.get("min_consecutive"), int) or cfg["min_consecutive"] < 1:
        raise ValueError("min_consecutive: must be an integer >= 1")
    if not isinstance(cfg.get("cooldown_s"), (int, float)) or cfg["cooldown_s"] < 0:
        raise ValueError("cooldown_s: must be >= 0")
    if cfg.get("model_complexity") not in (0, 1):
        raise ValueError("model_complexity: must be 0 or 1")
    bridge = cfg.get("bridge")
    if not isinstance(bridge, dict) or not isinstance(bridge.get("host"), str):
        raise ValueError("bridge: needs host (string) and port (integer)")
    if not isinstance(bridge.get("port"), int) or not 0 < bridge["port"] < 65536:
        raise ValueError("bridge.port: must be an integer in 1..65535")
    configured = cfg.get("model") or ""
    if configured and not isinstance(configured, str):
        raise ValueError("model: must be a file name")
    user = user_model_path()
    cfg["model"] = configured or (user if os.path.isfile(user) else DEFAULT_MODEL)
    cfg["teach_model"] = configured if configured and os.path.abspath(configured) != DEFAULT_MODEL else user
    return cfg


def check_mapping(mapping: dict, classes: list[str]) -> list[str]:
    """Check the gesture mapping against a model's classes.

    Args:
        mapping: gesture class -> command.
        classes: the model's classes.

    Returns:
        Model gestures that have no command (they are recognised but never sent).

    Raises:
        ValueError: if the mapping names a class the model does not know.
    """
    unknown = sorted(set(mapping) - set(classes))
    if unknown:
        raise ValueError("gestures: %s are not classes of the model (%s)" % (unknown, ", ".join(classes)))
    return sorted(c for c in classes if c != "none" and c not in mapping)
