"""Bounded per-client queue of outgoing frames (a slow client costs bounded memory, never delays others)."""

import collections
from typing import Any, Callable

__all__ = ["OutQueue"]


class OutQueue:
    """Bounded FIFO of frames for one client.

    Over ``max_frames`` or ``max_bytes`` the oldest frames are dropped. A topic frame may also carry a
    per-topic limit (the subscription's ``queue_length``): then only that topic's newest frames are kept.
    """

    def __init__(self, max_frames: int = 1000, max_bytes: int = 1 << 24, notify: Callable[..., Any] = None) -> None:
        """Create an empty queue; notify() is called when a frame arrives in an empty queue."""
        self.max_frames = max_frames
        self.max_bytes = max_bytes
        self.notify = notify
        self._queue = collections.deque()  # [frame, topic] entries; frame None once dropped
        self._per_topic = collections.defaultdict(collections.deque)  # the live entries of each topic
        self.bytes = 0
        self.frames = 0
        self.dropped = 0
        self.held = 0

    def __len__(self) -> int:
        """Number of live frames."""
        return self.frames

    def push(self, frame: Any, topic: str = None, topic_limit: int = 0) -> None:
        """Append frame; drop old frames to respect the bounds."""
        entry = [frame, topic]
        was_empty = self.frames == 0
        self._queue.append(entry)
        self.frames += 1
        self.bytes += len(frame)
        if topic is not None:
            per = self._per_topic[topic]
            per.append(entry)
            while 0 < topic_limit < len(per):  # the oldest frame of topic goes; its entry stays, dead
                dead = per.popleft()
                self.frames -= 1
                self.bytes -= len(dead[0])
                self.dropped += 1
                dead[0] = None
        while self.frames > self.max_frames or (self.bytes > self.max_bytes and self.frames > 1):
            self.pop()  # the oldest goes first
            self.dropped += 1
        if was_empty and self.notify is not None and not self.held:
            self.notify()

    def hold(self) -> None:
        """Collect pushes without notifying (a batch), until the matching :meth:`release`."""
        self.held += 1

    def release(self) -> None:
        """End a :meth:`hold`; notify once if frames are waiting."""
        self.held -= 1
        if not self.held and self.frames and self.notify is not None:
            self.notify()

    def pop(self) -> Any:
        """Return the oldest live frame, or None when empty."""
        while self._queue:
            frame, topic = self._queue.popleft()
            if frame is not None:  # the oldest live frame of its topic too: the per-topic limit drops from the front
                if topic is not None:
                    per = self._per_topic[topic]
                    per.popleft()
                    if not per:
                        del self._per_topic[topic]
                self.frames -= 1
                self.bytes -= len(frame)
                return frame
        return None
