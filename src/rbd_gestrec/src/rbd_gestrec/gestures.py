"""Gesture -> command mapping and a one-shot "last gesture" slot. ROS-free."""

from typing import Any, Dict, List, Mapping, Optional


class GestureConfigError(ValueError):
    """Raised when the gesture mapping is invalid."""


def parse_mapping(data: Any) -> Dict[str, str]:
    """Validate the gesture -> command mapping.

    Args:
        data: ``{"gestures": {label: command}}`` or the inner mapping, as loaded from YAML.

    Returns:
        Label -> command, labels and commands stripped.

    Raises:
        GestureConfigError: if the mapping is empty or has non-string/empty entries.
    """
    if isinstance(data, Mapping) and "gestures" in data:
        data = data["gestures"]
    if not isinstance(data, Mapping) or not data:
        raise GestureConfigError("gestures must be a non-empty mapping of gesture label -> trick command")
    mapping = {}
    for label, command in data.items():
        if not isinstance(label, str) or not label.strip():
            raise GestureConfigError("gesture labels must be non-empty strings, got %r" % (label,))
        if not isinstance(command, str) or not command.strip():
            raise GestureConfigError("gestures.%s must map to a non-empty command string, got %r" % (label, command))
        mapping[label.strip()] = command.strip()
    return mapping


def trick_names(data: Any) -> List[str]:
    """Names of the tricks of rbd_navigation's tricks YAML (only the names are used here).

    Args:
        data: ``{"tricks": {name: steps}}``, the inner mapping, a list of names, or None.

    Returns:
        The trick names, stripped (empty for None).

    Raises:
        GestureConfigError: if the names are not non-empty strings.
    """
    if data is None:
        return []
    if isinstance(data, Mapping) and "tricks" in data:
        data = data["tricks"]
    names = list(data.keys()) if isinstance(data, Mapping) else data
    if not isinstance(names, list):
        raise GestureConfigError("tricks must be a mapping or a list of trick names, got %r" % (data,))
    for name in names:
        if not isinstance(name, str) or not name.strip():
            raise GestureConfigError("trick names must be non-empty strings, got %r" % (name,))
    return [name.strip() for name in names]


def with_tricks(mapping: Mapping[str, str], tricks: List[str]) -> Dict[str, str]:
    """The gesture mapping plus every trick name as a label for itself.

    A laptop app that publishes a trick's own name (a gesture taught for that trick in teach
    mode) is then understood without a mapping entry for it; labels of the mapping keep
    their command.
    """
    out = dict(mapping)
    for name in tricks:
        out.setdefault(name, name)
    return out


class GestureBuffer:
    """Keeps the newest known gesture's command until it is taken once.

    Args:
        mapping: gesture label -> command (see parse_mapping).
        max_age: a gesture older than this when taken is dropped [s]; <= 0 keeps it forever.
    """

    def __init__(self, mapping: Mapping[str, str], max_age: float = 0.0) -> None:
        self.mapping = dict(mapping)
        self.max_age = float(max_age)
        self._pending = None  # type: Optional[Tuple[str, float]]

    def push(self, label: str, now: float) -> Optional[str]:
        """Record a gesture label received at time now [s].

        Returns:
            The command it maps to, or None if the label is unknown (then nothing changes).
        """
        if not isinstance(label, str):
            return None
        command = self.mapping.get(label.strip())
        if command is None:
            return None
        self._pending = (command, now)
        return command

    def take(self, now: float) -> str:
        """Return the pending command once and clear it; "" when none (or too old)."""
        pending, self._pending = self._pending, None
        if pending is None:
            return ""
        command, stamp = pending
        if self.max_age > 0.0 and now - stamp > self.max_age:
            return ""
        return command
