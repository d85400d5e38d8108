"""Gestures taught from a few shows: a fixed path embedding, nearest examples, rejection.

Embedding (:func:`embed`) of one classifier window of key points:

1. the palm centre's path, in units of the hand's size (wrist to middle-finger base), so the
   position and the distance of the hand do not matter, smoothed against camera shake
   (:func:`~rbd_local.gestures.features.palm_path`, the classifier's path too);
2. the *active* part of the path: from where 4 % of the path length is covered to where
   96 % is, so a gesture made early or late in the window, fast or slowly, gives the same
   points; it is resampled to :data:`POINTS` points evenly spaced in time;
3. those points with their mean removed and divided by their RMS size: the path's *shape*;
4. the log of that RMS size (the amplitude) and the active part's share of the window (the
   speed) as two extra numbers.

Distance between two embeddings: the RMS distance between the shape points plus
:data:`AMPLITUDE_WEIGHT` times the difference of the log amplitudes plus
:data:`DURATION_WEIGHT` times the difference of the durations.

Decision (:class:`TaughtGestures`): a window is a taught gesture ``g`` when its distance to
the nearest show of ``g`` is

- below ``g``'s own radius (from how much its shows differ from each other), and
- clearly smaller than its distance to anything else: the shows of the other taught gestures
  and a bank of synthetic windows of the four built-in gestures and of random motion (the
  ``none`` class). The confidence is ``d_else / (d_g + d_else)`` (0.5 = equally near), and it
  must reach the threshold.

So a still hand, random motion and the built-in gestures are rejected by construction, and
nothing is learned from the visitor but the shows themselves.
"""

import numpy as np

from rbd_local.gestures import features

NONE = "none"
POINTS = 16
AMPLITUDE_WEIGHT = 0.5
DURATION_WEIGHT = 0.5
MIN_AMPLITUDE = 0.02  # hand sizes; the log amplitude of a still hand stops here
MIN_PATH = 0.3  # hand sizes; a shorter path has no active part (the whole window is used)
RADIUS_FACTOR = 2.5
RADIUS_MIN = 0.45
RADIUS_MAX = 0.9
DEFAULT_THRESHOLD = 0.6
MIN_SHOWS = 3
EMBED_SIZE = 2 * POINTS + 2


def embed(window: np.ndarray) -> np.ndarray:
    """Embedding of one window (see the module docstring).

    Args:
        window: (T >= 4, 21, 2|3) key points in pixels, evenly spaced in time.

    Returns:
        (EMBED_SIZE,) vector: 2 * POINTS shape coordinates, log amplitude, duration share.

    Raises:
        ValueError: on a wrong shape, non-finite values or a zero-size hand.
    """
    w = np.asarray(window, dtype=np.float64)
    if w.ndim != 3 or w.shape[1] != 21 or w.shape[2] < 2 or w.shape[0] < 4:
        raise ValueError("window must be (T>=4, 21, 2|3), got %s" % (w.shape,))
    if not np.all(np.isfinite(w)):
        raise ValueError("window contains NaN or infinite key points")
    path, _ = features.palm_path(w)
    n = len(path)
    cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
    total = cum[-1]
    idx = np.arange(n, dtype=np.float64)
    if total < MIN_PATH:
        t0, t1 = 0.0, float(n - 1)
    else:
        t0 = float(np.interp(0.04 * total, cum, idx))
        t1 = float(np.interp(0.96 * total, cum, idx))
        if t1 - t0 < 3.0:
            mid = 0.5 * (t0 + t1)
            t0, t1 = max(0.0, mid - 1.5), min(n - 1.0, mid + 1.5)
    grid = np.linspace(t0, t1, POINTS)
    pts = np.stack([np.interp(grid, idx, path[:, i]) for i in range(2)], axis=1)
    pts -= pts.mean(axis=0)
    amp = float(np.sqrt((pts**2).sum(axis=1).mean()))
    shape = pts / max(amp, 1e-3)
    return np.concatenate([shape.ravel(), [np.log(max(amp, MIN_AMPLITUDE)), (t1 - t0) / (n - 1)]])


def embed_batch(windows: np.ndarray) -> np.ndarray:
    """Embeddings of a stack of windows, (N, T, 21, D) -> (N, EMBED_SIZE)."""
    return np.stack([embed(w) for w in windows]) if len(windows) else np.empty((0, EMBED_SIZE))


def distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances between embeddings, (N, E) x (M, E) -> (N, M) (or (E,) x (M, E) -> (M,))."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    single = a.ndim == 1
    a2 = np.atleast_2d(a)
    k = 2 * POINTS
    sa = a2[:, :k].reshape(len(a2), 1, POINTS, 2)
    sb = b[:, :k].reshape(1, len(b), POINTS, 2)
    shape = np.sqrt(((sa - sb) ** 2).sum(axis=3).mean(axis=2))
    amp = np.abs(a2[:, None, k] - b[None, :, k])
    dur = np.abs(a2[:, None, k + 1] - b[None, :, k + 1])
    d = shape + AMPLITUDE_WEIGHT * amp + DURATION_WEIGHT * dur
    return d[0] if single else d


def radius(examples: np.ndarray) -> float:
    """Acceptance radius of one gesture from its shows' embeddings (at least two).

    Each show's distance to its nearest other show says how much a performance varies;
    the radius is :data:`RADIUS_FACTOR` times the largest of them, kept within
    [:data:`RADIUS_MIN`, :data:`RADIUS_MAX`].
    """
    e = np.asarray(examples)
    if len(e) < 2:
        return RADIUS_MIN
    d = distances(e, e)
    np.fill_diagonal(d, np.inf)
    return float(np.clip(RADIUS_FACTOR * d.min(axis=1).max(), RADIUS_MIN, RADIUS_MAX))


_BANKS = {}


def negative_bank(samples: int, seed: int = 7, per_kind: int = 60) -> np.ndarray:
    """Embeddings of synthetic windows a taught gesture must not be confused with.

    The four built-in gestures and the random motions (still, wandering, aimless moves) of
    :mod:`rbd_local.gestures.synthetic`; not its "unknown gestures" (swipes left or up,
    diagonals, ...), which are exactly what visitors may want to teach. Cached per arguments.

    Returns:
        (7 * per_kind, EMBED_SIZE) embeddings.
    """
    from rbd_local.gestures import synthetic

    key = (int(samples), int(seed), int(per_kind))
    if key not in _BANKS:
        w, _, _ = synthetic.dataset(seed, per_kind, per_kind, samples, kinds=synthetic.RANDOM_KINDS)
        _BANKS[key] = embed_batch(w)
    return _BANKS[key]


class TaughtGestures:
    """The taught gestures of a model: their shows, their tricks and the decision."""

    def __init__(self, samples: int, threshold: float = DEFAULT_THRESHOLD, bank_seed: int = 7,
                 bank_per_kind: int = 60) -> None:
        """An empty set.

        Args:
            samples: frames per window (the model's).
            threshold: minimum confidence of a taught gesture, in (0.5, 1).
            bank_seed: seed of the synthetic negative bank.
            bank_per_kind: synthetic windows per kind in the bank.

        Raises:
            ValueError: on a bad threshold.
        """
        if not 0.5 < float(threshold) < 1.0:
            raise ValueError("taught-gesture threshold must be in (0.5, 1), got %r" % threshold)
        self.samples = int(samples)
        self.threshold = float(threshold)
        self.bank_seed = int(bank_seed)
        self.bank_per_kind = int(bank_per_kind)
        self.names: list[str] = []
        self.commands: dict[str, str] = {}
        self.windows: dict[str, np.ndarray] = {}
        self._emb: dict[str, np.ndarray] = {}
        self._radius: dict[str, float] = {}

    def __len__(self) -> int:
        """Number of taught gestures."""
        return len(self.names)

    @property
    def bank(self) -> np.ndarray:
        """The negative bank's embeddings."""
        return negative_bank(self.samples, self.bank_seed, self.bank_per_kind)

    def add(self, name: str, command: str, windows: np.ndarray) -> None:
        """Teach (or re-teach) gesture ``name`` from its shows.

        Args:
            name: gesture name (not ``none``).
            command: the trick it triggers.
            windows: (K >= MIN_SHOWS, samples, 21, 3) one window per show.

        Raises:
            ValueError: on a bad name, command or windows.
        """
        w = np.asarray(windows, dtype=np.float64)
        if not isinstance(name, str) or not name.strip() or name.strip() == NONE or name != name.strip():
            raise ValueError("gesture name must be a non-empty word other than 'none', got %r" % (name,))
        if not isinstance(command, str) or not command.strip():
            raise ValueError("command must be a non-empty trick name")
        if w.ndim != 4 or w.shape[1:3] != (self.samples, 21) or len(w) < MIN_SHOWS:
            raise ValueError("need at least %d shows of shape (%d, 21, 3), got %s" % (MIN_SHOWS, self.samples, w.shape))
        emb = embed_batch(w)
        if name not in self.names:
            self.names.append(name)
        self.commands[name] = command.strip()
        self.windows[name] = w
        self._emb[name] = emb
        self._radius[name] = radius(emb)

    def remove(self, name: str) -> None:
        """Forget gesture ``name``.

        Raises:
            KeyError: if it was not taught.
        """
        if name not in self.names:
            raise KeyError("no taught gesture %r (taught: %s)" % (name, ", ".join(self.names) or "none"))
        self.names.remove(name)
        for table in (self.commands, self.windows, self._emb, self._radius):
            table.pop(name, None)

    def radius_of(self, name: str) -> float:
        """Acceptance radius of a taught gesture."""
        return self._radius[name]

    def scores(self, emb: np.ndarray) -> dict[str, tuple[float, float]]:
        """Per taught gesture: (distance to its nearest show, confidence) for one embedding."""
        if not self.names:
            return {}
        bank_d = float(distances(emb, self.bank).min())
        nearest = {n: float(distances(emb, self._emb[n]).min()) for n in self.names}
        out = {}
        for n in self.names:
            other = min([bank_d] + [nearest[m] for m in self.names if m != n])
            out[n] = (nearest[n], other / (nearest[n] + other + 1e-12))
        return out

    def classify(self, window: np.ndarray, threshold: float = None) -> tuple[str, float, dict]:
        """Decide one window.

        Args:
            window: (T, 21, 3) key points.
            threshold: confidence override.

        Returns:
            (label or ``none``, confidence of the best taught gesture, {name: confidence}).

        Raises:
            ValueError: on a bad window (see :func:`embed`).
        """
        if not self.names:
            return NONE, 0.0, {}
        thr = self.threshold if threshold is None else float(threshold)
        sc = self.scores(embed(window))
        best = max(self.names, key=lambda n: sc[n][1])
        dist, conf = sc[best]
        confs = {n: sc[n][1] for n in self.names}
        if conf >= thr and dist <= self._radius[best]:
            return best, conf, confs
        return NONE, conf, confs
