"""Node parameters as rosbridge's launch files pass them (``"None"``, strings, numbers). ROS-free."""

from typing import Any, Callable, Optional

__all__ = ["ParamError", "number"]

_UNSET = ("", "none", "null", "default")


class ParamError(ValueError):
    """A parameter has a value that cannot be used."""


def number(
    name: str, value: Any, default: Any, kind: Callable[[Any], Any] = int, minimum: Optional[float] = None
) -> Any:
    """Parameter name's value as ``kind`` (int or float); None, ``"None"`` or an empty text mean ``default``.

    Raises:
        ParamError: The value is a boolean, not a number, or below ``minimum``.
    """
    if value is None or (isinstance(value, str) and value.strip().lower() in _UNSET):
        return default
    if isinstance(value, bool):
        raise ParamError("~%s must be a number, not %r" % (name, value))
    try:
        whole = kind is int and isinstance(value, (float, str))  # "1e6", 4096.0: whole numbers only
        parsed = kind(float(value) if whole else value)
        if whole and parsed != float(value):
            raise ValueError(value)
    except (TypeError, ValueError, OverflowError):
        wanted = "an integer" if kind is int else "a number"
        raise ParamError("~%s must be %s, not %r" % (name, wanted, value)) from None
    if parsed != parsed:
        raise ParamError("~%s must be a number, not NaN" % name)
    if minimum is not None and parsed < minimum:
        raise ParamError("~%s must be >= %s, not %r" % (name, minimum, value))
    return parsed
