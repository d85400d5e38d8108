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
========================  ==========================================================
"""

import os

import numpy as np

from rbd_local.gestures import features

FORMAT = "rbd_local.gesture_model"
FORMAT_VERSION = 1
NONE = "none"


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

    @property
    def gestures(self) -> list[str]:
        """Class names without the rejection class."""
        return [c for c in self.classes if c != NONE]

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

    def save(self, path: str) -> None:
        """Write the model to ``path`` (.npz)."""
        directory = os.path.dirname(os.path.abspath(path))
        os.makedirs(directory, exist_ok=True)
        with open(path, "wb") as fh:
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
            )

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
            if version != FORMAT_VERSION:
                raise ValueError("%s has model format version %d; this code reads %d" % (path, version, FORMAT_VERSION))
            names = [str(n) for n in data["feature_names"]]
            if names != features.feature_names():
                raise ValueError("%s was trained on other features; retrain it with rbd-train" % path)
            return cls(
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
