"""The gesture classifier and its file format.

A model is a multinomial logistic regression (trained with scikit-learn, as the original
system) stored as a plain ``.npz`` file without pickles, so loading it runs no code:

========================  ==========================================================
key                       content
========================  ==========================================================
``format``                ``"rbd_local.gesture_model"``
``version``               format version (:data:`FORMAT_VERSION`)
``classes``               class names; ``none`` is the rejection class
``coef``, ``intercept``   logistic regression weights on standardised features
``mean``, ``scale``       feature standardisation
``feature_names``         must equal :func:`features.feature_names` at load time
``samples``, ``window_s`` frames per window and window length [s]
``threshold``             confidence below which nothing is sent
``provenance``            free text: how the model was made (data, seed, command)
``revision``, ``history`` version 2: a counter raised by every teach / forget, and
                          one line per change (what, when)
``taught_*``              version 2: the taught gestures (:mod:`.fewshot`): names,
                          tricks, every show's key-point window, the threshold and
                          the negative bank's seed and size
========================  ==========================================================

Version 1 files (no taught gestures) are still read; :meth:`GestureModel.save` writes
version 2.
"""

import os
import shutil
import time

import numpy as np

from rbd_local.compat import zip_strict
from rbd_local.gestures import features, fewshot

FORMAT = "rbd_local.gesture_model"
FORMAT_VERSION = 2
READABLE_VERSIONS = (1, 2)
NONE = "none"


class TeachConflictError(ValueError):
    """The shows of a gesture to teach look like a gesture the model already knows."""


class GestureModel:
    """Logistic-regression gesture classifier evaluated with numpy alone."""

    def __init__(
        self,
        classes: list[str],
        coef: np.ndarray,
        intercept: np.ndarray,
        mean: np.ndarray,
        scale: np.ndarray,
        samples: int,
        window_s: float,
        threshold: float,
        provenance: str = "",
    ) -> None:
        """Create a model from its parameters.

        Args:
            classes: class names, one of them ``none``.
            coef: (C, F) weights.
            intercept: (C,) biases.
            mean: (F,) feature means.
            scale: (F,) feature standard deviations (> 0).
            samples: frames per window.
            window_s: window length [s].
            threshold: minimum confidence to report a gesture, in (0, 1].
            provenance: how the model was made.

        Raises:
            ValueError: on inconsistent shapes or values.
        """
        self.classes = [str(c) for c in classes]
        self.coef = np.asarray(coef, dtype=np.float64)
        self.intercept = np.asarray(intercept, dtype=np.float64)
        self.mean = np.asarray(mean, dtype=np.float64)
        self.scale = np.asarray(scale, dtype=np.float64)
        c, f = len(self.classes), features.NUM_FEATURES
        if NONE not in self.classes or len(set(self.classes)) != c or c < 2:
            raise ValueError("classes must be unique and include %r: %s" % (NONE, self.classes))
        if self.coef.shape != (c, f) or self.intercept.shape != (c,):
            raise ValueError("coef/intercept shapes %s/%s do not match %d classes x %d features"
                             % (self.coef.shape, self.intercept.shape, c, f))
        if self.mean.shape != (f,) or self.scale.shape != (f,) or np.any(self.scale <= 0):
            raise ValueError("mean/scale must be (%d,) with positive scale" % f)
        if not all(np.all(np.isfinite(a)) for a in (self.coef, self.intercept, self.mean, self.scale)):
            raise ValueError("model parameters must be finite")
        if int(samples) < 4 or not float(window_s) > 0:
            raise ValueError("samples must be >= 4 and window_s > 0")
        if not 0.0 < float(threshold) <= 1.0:
            raise ValueError("threshold must be in (0, 1], got %r" % threshold)
        self.samples = int(samples)
        self.window_s = float(window_s)
        self.threshold = float(threshold)
        self.provenance = str(provenance)
        self.taught = fewshot.TaughtGestures(self.samples)
        self.revision = 0
        self.history: list[str] = []

    @property
    def gestures(self) -> list[str]:
        """Built-in class names without the rejection class."""
        return [c for c in self.classes if c != NONE]

    @property
    def labels(self) -> list[str]:
        """Every gesture the model can report: the built-in classes, then the taught ones."""
        return self.gestures + list(self.taught.names)

    def taught_commands(self) -> dict[str, str]:
        """Taught gesture -> its trick."""
        return dict(self.taught.commands)

    def classify(self, window: np.ndarray, threshold: float = None) -> tuple[str, float, dict]:
        """Decide one window with the built-in classifier and the taught gestures.

        A taught gesture wins when it is recognised (its own rejection rules, see
        :mod:`.fewshot`, make built-in gestures and random motion fall outside it);
        otherwise the logistic regression decides with ``threshold``.

        Args:
            window: (T, 21, 3) key points, evenly spaced in time.
            threshold: built-in classifier threshold (default: the model's).

        Returns:
            (label or ``none``, its confidence, {label: confidence} for every gesture).

        Raises:
            ValueError: on a bad window.
        """
        proba = self.predict_proba(window)
        label, conf = self.decide(proba, threshold)
        scores = {c: float(p) for c, p in zip_strict(self.classes, proba) if c != NONE}
        if len(self.taught):
            t_label, t_conf, t_scores = self.taught.classify(window)
            scores.update(t_scores)
            if t_label != NONE:
                return t_label, t_conf, scores
        return label, conf, scores

    def teach(self, name: str, command: str, windows: np.ndarray, force: bool = False) -> dict:
        """Add (or replace) a taught gesture.

        Args:
            name: the new gesture's name (not a built-in class, not ``none``).
            command: the trick it triggers.
            windows: (K >= 3, samples, 21, 3) one window per show.
            force: teach even when the shows look like a gesture the model already knows.

        Returns:
            {"name", "command", "shows", "radius", "built_in": {class: shows decided as it},
            "taught": {gesture: shows recognised as it}}.

        Raises:
            ValueError: on a bad name or bad windows.
            TeachConflictError: when at least half the shows are recognised as one known gesture
                (and ``force`` is False).
        """
        if name in self.classes:
            raise ValueError("%r is a built-in class of the model; choose another name" % name)
        w = np.asarray(windows, dtype=np.float64)
        built_in, taught = {}, {}
        for win in w:
            label, _ = self.decide(self.predict_proba(win))
            if label != NONE:
                built_in[label] = built_in.get(label, 0) + 1
            if len(self.taught):
                t_label, _, _ = self.taught.classify(win)
                if t_label != NONE and t_label != name:
                    taught[t_label] = taught.get(t_label, 0) + 1
        clash = {k: v for k, v in list(built_in.items()) + list(taught.items()) if 2 * v >= len(w)}
        if clash and not force:
            raise TeachConflictError("the shows look like %s; teach a more different gesture (or force it)"
                                % ", ".join("%r (%d of %d shows)" % (k, v, len(w)) for k, v in clash.items()))
        self.taught.add(name, command, w)
        self._changed("taught %r -> %r from %d shows" % (name, command, len(w)))
        return {"name": name, "command": command, "shows": int(len(w)), "radius": self.taught.radius_of(name),
                "built_in": built_in, "taught": taught}

    def forget(self, name: str) -> None:
        """Remove a taught gesture (the reverse of :meth:`teach`).

        Raises:
            KeyError: if ``name`` was not taught.
        """
        self.taught.remove(name)
        self._changed("forgot %r" % name)

    def _changed(self, what: str) -> None:
        self.revision += 1
        self.history.append("r%d %s: %s" % (self.revision, time.strftime("%Y-%m-%d %H:%M:%S"), what))

    def predict_proba_features(self, feats: np.ndarray) -> np.ndarray:
        """Class probabilities for feature vectors, (F,) -> (C,) or (N, F) -> (N, C)."""
        x = (np.asarray(feats, dtype=np.float64) - self.mean) / self.scale
        z = x @ self.coef.T + self.intercept
        z = z - z.max(axis=-1, keepdims=True)
        e = np.exp(z)
        return e / e.sum(axis=-1, keepdims=True)

    def predict_proba(self, window: np.ndarray) -> np.ndarray:
        """Class probabilities of one window of key points, (T, 21, D) -> (C,)."""
        return self.predict_proba_features(features.window_features(window))

    def decide(self, proba: np.ndarray, threshold: float = None) -> tuple[str, float]:
        """Turn probabilities into a decision.

        Args:
            proba: (C,) class probabilities.
            threshold: override of the model's threshold.

        Returns:
            (label, confidence); label is ``none`` when the best class is ``none`` or its
            probability is below the threshold.
        """
        thr = self.threshold if threshold is None else float(threshold)
        best = int(np.argmax(proba))
        conf = float(proba[best])
        label = self.classes[best]
        if label == NONE or conf < thr:
            return NONE, conf
        return label, conf

    def save(self, path: str, keep_previous: bool = False) -> None:
        """Write the model to ``path`` (.npz), atomically.

        Args:
            path: output file.
            keep_previous: first copy an existing file at ``path`` to ``path + ".prev"``
                (one step of undo: ``rbd-teach --undo``).
        """
        directory = os.path.dirname(os.path.abspath(path))
        os.makedirs(directory, exist_ok=True)
        t = self.taught
        names = list(t.names)
        shows = [t.windows[n] for n in names]
        if keep_previous and os.path.isfile(path):
            shutil.copyfile(path, path + ".prev")
        tmp = path + ".part"
        with open(tmp, "wb") as fh:
            np.savez(
                fh,
                format=np.array(FORMAT),
                version=np.array(FORMAT_VERSION),
                classes=np.array(self.classes),
                coef=self.coef,
                intercept=self.intercept,
                mean=self.mean,
                scale=self.scale,
                feature_names=np.array(features.feature_names()),
                samples=np.array(self.samples),
                window_s=np.array(self.window_s),
                threshold=np.array(self.threshold),
                provenance=np.array(self.provenance),
                revision=np.array(self.revision),
                history=np.array(self.history, dtype=str).reshape(-1),
                taught_names=np.array(names, dtype=str).reshape(-1),
                taught_commands=np.array([t.commands[n] for n in names], dtype=str).reshape(-1),
                taught_counts=np.array([len(s) for s in shows], dtype=np.int64),
                taught_windows=(np.concatenate(shows) if shows else np.empty((0, self.samples, 21, 3))),
                taught_threshold=np.array(t.threshold),
                taught_bank=np.array([t.bank_seed, t.bank_per_kind], dtype=np.int64),
            )
        os.replace(tmp, path)

    @classmethod
    def load(cls, path: str) -> "GestureModel":
        """Read a model written by :meth:`save`.

        Raises:
            ValueError: if the file is not a gesture model, has another format version or
                was made for different features.
            OSError: if the file cannot be read.
        """
        try:
            data = np.load(path, allow_pickle=False)
        except ValueError as exc:
            raise ValueError("%s is not a gesture model: %s" % (path, exc)) from exc
        with data:
            if "format" not in data.files or str(data["format"]) != FORMAT:
                raise ValueError("%s is not a gesture model (no format tag %r)" % (path, FORMAT))
            version = int(data["version"])
            if version not in READABLE_VERSIONS:
                raise ValueError("%s has model format version %d; this code reads %s"
                                 % (path, version, ", ".join(str(v) for v in READABLE_VERSIONS)))
            names = [str(n) for n in data["feature_names"]]
            if names != features.feature_names():
                raise ValueError("%s was trained on other features; retrain it with rbd-train" % path)
            model = cls(
                classes=[str(c) for c in data["classes"]],
                coef=data["coef"],
                intercept=data["intercept"],
                mean=data["mean"],
                scale=data["scale"],
                samples=int(data["samples"]),
                window_s=float(data["window_s"]),
                threshold=float(data["threshold"]),
                provenance=str(data["provenance"]),
            )
            if version >= 2:
                model.revision = int(data["revision"])
                model.history = [str(h) for h in data["history"]]
                seed, per_kind = (int(v) for v in data["taught_bank"])
                model.taught = fewshot.TaughtGestures(model.samples, float(data["taught_threshold"]), seed, per_kind)
                windows = data["taught_windows"]
                start = 0
                for name, command, count in zip_strict(data["taught_names"], data["taught_commands"],
                                                       data["taught_counts"]):
                    model.taught.add(str(name), str(command), windows[start:start + int(count)])
                    start += int(count)
            return model


def train(
    feats: np.ndarray,
    labels: np.ndarray,
    samples: int,
    window_s: float,
    threshold: float,
    c_reg: float = 1.0,
    provenance: str = "",
) -> GestureModel:
    """Fit a logistic regression on feature vectors.

    Args:
        feats: (N, F) features.
        labels: (N,) class names (must include ``none``).
        samples: frames per window the features were computed on.
        window_s: window length [s].
        threshold: confidence threshold stored in the model.
        c_reg: inverse regularisation strength (scikit-learn's ``C``).
        provenance: free text stored in the model.

    Returns:
        The trained model.
    """
    from sklearn.linear_model import LogisticRegression

    feats = np.asarray(feats, dtype=np.float64)
    labels = np.asarray(labels).astype(str)
    mean = feats.mean(axis=0)
    scale = feats.std(axis=0)
    scale[scale < 1e-9] = 1.0
    clf = LogisticRegression(C=c_reg, max_iter=2000)
    clf.fit((feats - mean) / scale, labels)
    return GestureModel(
        classes=list(clf.classes_),
        coef=clf.coef_,
        intercept=clf.intercept_,
        mean=mean,
        scale=scale,
        samples=samples,
        window_s=window_s,
        threshold=threshold,
        provenance=provenance,
    )
