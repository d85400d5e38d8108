"""What newer Pythons have built in, for Python 3.9 (the oldest with current MediaPipe wheels)."""

from collections.abc import Iterator, Sized
from typing import Any

__all__ = ["zip_strict"]


def zip_strict(*seqs: Sized) -> Iterator[tuple[Any, ...]]:
    """``zip(*seqs, strict=True)`` of Python 3.10 for sequences of known length.

    Raises:
        ValueError: The sequences differ in length (before anything is yielded).
    """
    lengths = [len(s) for s in seqs]
    if len(set(lengths)) > 1:
        raise ValueError("zip_strict: sequences of different lengths %s" % lengths)
    return zip(*seqs)
