"""Hands followed over time: up to two hands, short losses bridged, the one that performs chosen.

Real footage (issue 26) loses a fast, blurred hand for 0.2-0.6 s in the middle of a swipe and
often shows a second hand that does nothing (resting at the side, near the face). MediaPipe
reports the hands of a frame in no fixed order, and with one hand allowed it may jump from one
hand to the other. So the recognizer and teach mode do not take "the" hand of a frame:

- every hand of a frame is given to the :class:`Track` whose last palm position is nearest
  (within :data:`MAX_JUMP` hand sizes plus what a fast hand covers in the time since,
  :data:`MAX_SPEED`); a hand far from every track starts a track of its own, so a jump to
  another hand never looks like a swipe. A lost hand found again farther on (up to
  :data:`MAX_SPEED_ONWARD`) continues its track only when it was already moving that way before
  it was lost (a fast swipe blurs out of view mid-motion) and its size is about the same. A hand
  that *vanished* (frames with no hand that could be it: a swipe blurred from its very start, the
  hand at rest before it) and is found again farther on, the only new hand, continues its track
  too, at the same size and not mirrored (:meth:`Track.rejoins`); a detector that jumps to
  another hand without a frame between never does;
- a track that has not been seen for more than ``max_gap_s`` (0.5 s) ends; a shorter loss is
  bridged: the window's frames are resampled in time (:func:`features.resample`), which fills
  the gap by straight-line interpolation of every key point between the frames before and after;
- of the tracks with a full window, the one whose palm travelled farthest in it performs
  (:func:`performer`).

ROS-free, numpy only.
"""

import numpy as np

from rbd_local.gestures.hand import MIDDLE_MCP, NUM_LANDMARKS, PALM, WRIST

#: Index and little finger bases (MediaPipe's numbering), for the hand's mirror sense.
INDEX_MCP = 5
PINKY_MCP = 17

#: Largest jump of the palm between two frames of the same hand [hand sizes], plus MAX_SPEED * dt.
MAX_JUMP = 2.5
#: Fastest palm motion followed across a loss [hand sizes / s] (a swipe of 7 hand lengths in 0.5 s).
MAX_SPEED = 30.0
#: Fastest palm motion followed across a loss when the hand was already moving that way before it
#: was lost [hand sizes / s] (a fast swipe: 7 hand lengths in 0.2-0.3 s, blurred out of MediaPipe's view).
MAX_SPEED_ONWARD = 80.0
#: Least palm speed before a loss for :data:`MAX_SPEED_ONWARD` [hand sizes / s], and the least cosine
#: between that motion and the jump across the loss.
ONWARD_SPEED = 2.0
ONWARD_COS = 0.7
#: Most a hand's size may change across such a jump (ratio).
ONWARD_SIZE_RATIO = 1.5
#: A hand whose mirror sense (:func:`chirality`) is clearer than this either way is not taken for a
#: hand of the other sense.
CHIRALITY_CLEAR = 0.25
#: Most hands followed at once.
MAX_TRACKS = 2
#: Longest loss of a hand that is bridged [s].
MAX_GAP_S = 0.5


def as_hands(keypoints: object) -> list:
    """The finite hands of one frame as a list of (21, 3) arrays.

    Args:
        keypoints: None, one (21, D) array, an (H, 21, D) array or a sequence of (21, D) arrays;
            hands with NaN (not found) are left out.
    """
    if keypoints is None:
        return []
    if isinstance(keypoints, np.ndarray) and keypoints.ndim == 2:
        hands = [keypoints]
    else:
        hands = list(keypoints)
    out = []
    for h in hands:
        if h is None:
            continue
        a = np.asarray(h, dtype=np.float64)
        if a.ndim == 2 and a.shape[0] == NUM_LANDMARKS and a.shape[1] >= 2 and np.all(np.isfinite(a)):
            out.append(a)
    return out


def palm_and_size(hand: np.ndarray) -> tuple:
    """Palm centre (2,) [px] and hand size (wrist to middle-finger base) [px] of one hand."""
    xy = hand[:, :2]
    return xy[list(PALM)].mean(axis=0), float(np.linalg.norm(xy[MIDDLE_MCP] - xy[WRIST]))


def chirality(hand: np.ndarray) -> float:
    """The hand's mirror sense in the image: the turn from the index to the little finger base about the wrist.

    Positive for one sense (a right palm facing the camera, or a left hand's back), negative for
    the mirrored one, near 0 for a hand seen edge-on; in units of the hand size squared. A hand
    keeps its sign while it moves and rolls; a swap to the visitor's other hand usually flips it.
    """
    xy = np.asarray(hand, dtype=np.float64)[:, :2]
    a, b = xy[INDEX_MCP] - xy[WRIST], xy[PINKY_MCP] - xy[WRIST]
    size2 = float(np.sum((xy[MIDDLE_MCP] - xy[WRIST]) ** 2))
    return float(a[0] * b[1] - a[1] * b[0]) / max(size2, 1e-9)


#: A hand has come to rest when its palm moved at most this much [hand sizes] over REST_S.
REST_MOTION = 0.3
REST_S = 0.15


#: Two hands of one frame whose palms are closer than this [hand sizes] are one hand seen twice.
DUPLICATE = 1.0


def dedupe(hands: list) -> list:
    """The hands of a frame without duplicates: MediaPipe sometimes reports a blurred hand twice."""
    kept, palms = [], []
    for hand in hands:
        palm, size = palm_and_size(hand)
        if any(np.linalg.norm(palm - p) < DUPLICATE * max(size, s) for p, s in palms):
            continue
        kept.append(hand)
        palms.append((palm, size))
    return kept


class Track:
    """One hand's frames: times, key points, when it was first and last seen, and when it settled.

    ``settled_t`` is when the hand first came to rest after it came into view (None while the
    motion it came into view with goes on): a hand raised into the frame is moving when it is
    first seen, and that motion is no gesture (issue 26). The recognizer classifies a window that
    begins before ``settled_t`` with the hand held at its place of rest until then.
    """

    __slots__ = ("times", "frames", "first_t", "palm", "size", "settled_t", "_entry", "vanished")

    def __init__(self, t: float, hand: np.ndarray) -> None:
        """Start a track with its first frame."""
        self.times = [float(t)]
        self.frames = [hand]
        self.first_t = float(t)
        self.palm, self.size = palm_and_size(hand)
        self.settled_t = None
        self._entry = [(float(t), self.palm)]
        #: whether, since this hand was last seen, a frame showed no hand that could have been it
        self.vanished = False

    @property
    def last_t(self) -> float:
        """Time of the last frame [s]."""
        return self.times[-1]

    def add(self, t: float, hand: np.ndarray) -> None:
        """Append one frame."""
        self.vanished = False
        self.times.append(float(t))
        self.frames.append(hand)
        palm, size = palm_and_size(hand)
        self.palm = palm
        self.size = 0.8 * self.size + 0.2 * size if size > 0 else self.size
        if self.settled_t is None:
            self._entry.append((float(t), palm))
            recent = [p for ts, p in self._entry if t - ts <= REST_S + 1e-9]
            if t - self._entry[0][0] >= REST_S and len(recent) >= 2:
                moved = float(np.ptp(np.array(recent), axis=0).max()) / max(self.size, 1e-6)
                if moved <= REST_MOTION:
                    # at rest: if it never moved since it appeared, it was at rest from the start
                    allp = np.array([p for _, p in self._entry])
                    still = float(np.ptp(allp, axis=0).max()) / max(self.size, 1e-6) <= REST_MOTION
                    self.settled_t = self.first_t if still else float(t) - REST_S
                    self._entry = []

    def forget_entry(self) -> None:
        """Treat the hand as long known (after a gesture: it did not just come into view)."""
        self.first_t, self.settled_t, self._entry = -np.inf, -np.inf, []

    def trim(self, t: float, keep_s: float) -> None:
        """Drop frames older than ``keep_s`` before ``t`` (one frame before that window is kept)."""
        while len(self.times) > 2 and t - self.times[1] >= keep_s:
            del self.times[0]
            del self.frames[0]

    def onward(self, t: float, palm: np.ndarray, size: float) -> bool:
        """Whether a hand found at ``palm`` after a loss continues this track's motion before the loss.

        Args:
            t: the frame time [s] (after :attr:`last_t`).
            palm: the found hand's palm centre [px].
            size: its hand size [px].
        """
        dt = t - self.last_t
        if len(self.frames) < 2 or dt <= 0 or self.size <= 0 or size <= 0:
            return False
        if max(size, self.size) / min(size, self.size) > ONWARD_SIZE_RATIO:
            return False
        step_t = self.times[-1] - self.times[-2]
        if step_t <= 0:
            return False
        v = (self.palm - palm_and_size(self.frames[-2])[0]) / step_t / self.size
        jump = (np.asarray(palm) - self.palm) / self.size
        speed, dist = float(np.linalg.norm(v)), float(np.linalg.norm(jump))
        if speed < ONWARD_SPEED or dist > MAX_JUMP + MAX_SPEED_ONWARD * dt:
            return False
        return float(np.dot(v, jump)) >= ONWARD_COS * speed * dist

    def rejoins(self, t: float, hand: np.ndarray) -> bool:
        """Whether a new hand found after this hand vanished is this hand again, farther on.

        A swipe blurred from its very start loses the hand while it is still at rest (no motion
        before the loss for :meth:`onward`) and MediaPipe finds it again where the swipe ends.
        It is taken for this hand when the hand *vanished* (a frame since it was last seen had no
        hand that could be it, so the detector did not merely switch to another hand), the found
        hand is within :data:`MAX_SPEED_ONWARD`, about as large (:data:`ONWARD_SIZE_RATIO`) and
        not mirrored (:func:`chirality`), and, if this hand was moving before the loss, the jump
        is the way it moved.
        """
        if not self.vanished:
            return False
        palm, size = palm_and_size(hand)
        dt = t - self.last_t
        if dt <= 0 or self.size <= 0 or size <= 0 or max(size, self.size) / min(size, self.size) > ONWARD_SIZE_RATIO:
            return False
        if float(np.linalg.norm(palm - self.palm)) / self.size > MAX_JUMP + MAX_SPEED_ONWARD * dt:
            return False
        c0, c1 = chirality(self.frames[-1]), chirality(hand)
        if min(abs(c0), abs(c1)) > CHIRALITY_CLEAR and c0 * c1 < 0:
            return False
        if len(self.frames) >= 2 and self.times[-1] > self.times[-2]:
            v = (self.palm - palm_and_size(self.frames[-2])[0]) / (self.times[-1] - self.times[-2]) / self.size
            speed = float(np.linalg.norm(v))
            if speed >= ONWARD_SPEED:
                return self.onward(t, palm, size)
        return True

    def travel(self) -> float:
        """Palm path length over the kept frames [hand sizes]."""
        if len(self.frames) < 2 or self.size <= 0:
            return 0.0
        palms = np.array([palm_and_size(f)[0] for f in self.frames])
        return float(np.linalg.norm(np.diff(palms, axis=0), axis=1).sum() / self.size)


class HandTracks:
    """Up to :data:`MAX_TRACKS` hands followed frame by frame (see the module docstring)."""

    def __init__(self, max_gap_s: float = MAX_GAP_S, max_tracks: int = MAX_TRACKS) -> None:
        """Create an empty set of tracks."""
        if max_gap_s <= 0 or int(max_tracks) < 1:
            raise ValueError("max_gap_s > 0 and max_tracks >= 1 required")
        self.max_gap_s = float(max_gap_s)
        self.max_tracks = int(max_tracks)
        self.tracks: list = []

    def reset(self) -> None:
        """Forget every track."""
        self.tracks = []

    def update(self, t: float, hands: list) -> list:
        """Add the hands of one frame.

        Args:
            t: frame time [s], increasing.
            hands: (21, 3) key-point arrays (:func:`as_hands`).

        Returns:
            The tracks that got a frame now.
        """
        self.tracks = [tr for tr in self.tracks if t - tr.last_t <= self.max_gap_s]
        hands = dedupe(hands)
        pairs = []
        for i, hand in enumerate(hands):
            palm, size = palm_and_size(hand)
            for j, tr in enumerate(self.tracks):
                unit = max(tr.size, size, 1e-6)
                dist = float(np.linalg.norm(palm - tr.palm)) / unit
                if dist <= MAX_JUMP + MAX_SPEED * max(t - tr.last_t, 0.0) or tr.onward(t, palm, size):
                    pairs.append((dist, i, j))
        pairs.sort()
        used_h, used_t, touched = set(), set(), []
        for _dist, i, j in pairs:
            if i in used_h or j in used_t:
                continue
            used_h.add(i)
            used_t.add(j)
            self.tracks[j].add(t, hands[i])
            touched.append(self.tracks[j])
        new = [i for i in range(len(hands)) if i not in used_h]
        lost = [tr for tr in self.tracks if tr not in touched and tr.rejoins(t, hands[new[0]])] if len(new) == 1 else []
        if len(lost) == 1:  # the only new hand is the one that vanished, found farther on
            lost[0].add(t, hands[new[0]])
            touched.append(lost[0])
            used_h.add(new[0])
            new = []
        for tr in self.tracks:
            if tr not in touched and not new:
                tr.vanished = True  # no hand of this frame can be it: it is out of the detector's sight
        for i in new:
            if len(self.tracks) >= self.max_tracks:
                # the stalest track that got nothing now makes room
                free = [tr for tr in self.tracks if tr not in touched]
                if not free:
                    continue
                self.tracks.remove(min(free, key=lambda tr: tr.last_t))
            tr = Track(t, hands[i])
            self.tracks.append(tr)
            touched.append(tr)
        return touched


def performer(tracks: list, t: float, window_s: float, min_fill: float = 0.9) -> object:
    """The track that performs: of those seen now with a full window, the farthest-travelled.

    Args:
        tracks: :class:`Track` objects (trimmed to the window).
        t: the current frame time [s].
        window_s: window length [s].
        min_fill: share of the window its frames must span.

    Returns:
        The track, or None when no track has a full window.
    """
    full = [tr for tr in tracks if tr.last_t == t and len(tr.times) >= 4
            and tr.times[-1] - tr.times[0] >= min_fill * window_s]
    if not full:
        return None
    return max(full, key=lambda tr: tr.travel())


def split_tracks(times: np.ndarray, keypoints: np.ndarray, max_gap_s: float = MAX_GAP_S) -> list:
    """A recording's hands as tracks (teach mode's shows, evaluation).

    Args:
        times: (K,) frame times [s].
        keypoints: (K, 21, 3) or (K, H, 21, 3) key points, NaN where no hand was found.
        max_gap_s: longest bridged loss [s].

    Returns:
        Every track ever followed, each as ((M,) times, (M, 21, 3) key points).
    """
    kp = np.asarray(keypoints, dtype=np.float64)
    if kp.ndim == 3:
        kp = kp[:, None]
    tracker = HandTracks(max_gap_s)
    done, alive = [], []
    for i, t in enumerate(np.asarray(times, dtype=np.float64)):
        frame = kp[i]
        before = list(tracker.tracks)
        tracker.update(float(t), as_hands(frame))
        done.extend(tr for tr in before if tr not in tracker.tracks)
        alive = tracker.tracks
    return [(np.array(tr.times), np.array(tr.frames)) for tr in done + list(alive)]
