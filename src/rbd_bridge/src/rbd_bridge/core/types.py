"""Types the core and the ROS edge share: errors, type names, typed arrays."""

from typing import Any

__all__ = ["BridgeError", "ConversionError", "TypedArray", "normalize_type"]


class BridgeError(Exception):
    """An op that cannot be done; sent to the client as a status (when it opted in)."""

    def __init__(self, text: str, level: str = "error") -> None:
        super().__init__(text)
        self.level = level


class ConversionError(ValueError):
    """A JSON value does not fit the ROS message type; the text names the field."""


class TypedArray:
    """A homogeneous numeric array of ROS element type ``kind`` (CBOR typed-array tags)."""

    __slots__ = ("kind", "values")

    def __init__(self, kind: str, values: Any) -> None:
        """Wrap values (a sequence of numbers, or bytes for uint8/char)."""
        self.kind = kind
        self.values = values


def normalize_type(type_name: Any) -> str:
    """The ROS 1 spelling ``pkg/Name`` of a type (``pkg/msg/Name``, ``pkg/srv/Name`` accepted); else ConversionError."""
    if not isinstance(type_name, str) or not type_name:
        raise ConversionError("type must be a non-empty string, got %r" % (type_name,))
    parts = type_name.strip("/").split("/")
    if len(parts) == 3 and parts[1] in ("msg", "srv", "action"):
        parts = [parts[0], parts[2]]
    if len(parts) != 2 or not all(p.replace("_", "a").isalnum() for p in parts):
        raise ConversionError("invalid type name %r" % (type_name,))
    return "/".join(parts)
