"""A small learned candidate classifier: is this blob the shuttle, judged by its looks alone?

Why this file exists: the paper's filters 1–3 (contour length, tilted-rectangle short side,
whiteness) are hard cut-offs on one measurement each; on real courts the shuttle differs from
hands, shoes, shirts, rackets and lights by a *combination* of them (small, bright above its own
surroundings, isolated, not saturated). A tiny multilayer perceptron on hand-crafted features
(``detector.FEATURE_NAMES``; the TV classifier also the blob's grey patch, ``PATCH_NAMES``)
turns them into one probability that the association step uses as the candidate's quality. It is numpy-only (OpenCV 5 ships no ``ml`` module) and its weights
live in a small JSON file shipped in ``resources/`` (``core/resources.py``), written by
``benchmarks/train_classifier.py``.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .resources import resource_path



class ClassifierError(ValueError):
    """A classifier file that is missing or malformed."""


class TrainingStopped(Exception):
    """Training gave up because its ``should_stop`` said so (the user stopped or closed)."""


# How many epochs pass between two looks at ``should_stop``: a look costs nothing beside an
# epoch, and ten epochs of the adaptation's training take well under a second.
_STOP_CHECK_EPOCHS = 10


@dataclass(frozen=True)
class CandidateClassifier:
    """Standardise → (dense + tanh)* → dense → sigmoid."""

    name: str
    mean: np.ndarray
    scale: np.ndarray
    weights: tuple[np.ndarray, ...]
    biases: tuple[np.ndarray, ...]
    feature_names: tuple[str, ...] = ()

    def probability(self, features: np.ndarray) -> np.ndarray:
        """(N, F) features → (N,) probabilities that each candidate is the shuttle."""
        h = (np.asarray(features, dtype=np.float64) - self.mean) / self.scale
        for k, (w, b) in enumerate(zip(self.weights, self.biases)):
            h = h @ w + b
            if k < len(self.weights) - 1:
                h = np.tanh(h)
        # np.minimum(np.maximum(...)) is np.clip's arithmetic without its Python wrappers (which
        # cost more than the rest of this call on a frame's few candidates).
        return 1.0 / (1.0 + np.exp(-np.minimum(np.maximum(h[:, 0], -30.0), 30.0)))

    def to_dict(self) -> dict:
        return {"name": self.name, "feature_names": list(self.feature_names),
                "mean": self.mean.tolist(), "scale": self.scale.tolist(),
                "weights": [w.tolist() for w in self.weights],
                "biases": [b.tolist() for b in self.biases]}

    def save(self, path: str | Path) -> None:
        Path(path).write_text(json.dumps(self.to_dict()) + "\n", encoding="utf-8")


def load_classifier(name_or_path: str) -> CandidateClassifier:
    """A shipped classifier by name (``resources/<name>.json``) or a classifier file by path."""
    path = Path(name_or_path)
    if path.suffix != ".json":
        path = resource_path(f"{name_or_path}.json")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        return CandidateClassifier(
            name=str(name_or_path), mean=np.asarray(data["mean"], float),
            scale=np.asarray(data["scale"], float),
            weights=tuple(np.asarray(w, float) for w in data["weights"]),
            biases=tuple(np.asarray(b, float) for b in data["biases"]),
            feature_names=tuple(data.get("feature_names", ())))
    except FileNotFoundError:
        raise ClassifierError(f"candidate classifier not found: {path}") from None
    except (KeyError, ValueError, TypeError) as exc:
        raise ClassifierError(f"candidate classifier {path} is malformed: {exc}") from None


def _adam(params: list, xs: np.ndarray, y: np.ndarray, sw: np.ndarray, epochs: int, learning_rate: float,
          anchors: list, decay: float, should_stop: Callable[[], bool] | None) -> list:
    """Full-batch Adam on the weighted cross-entropy of the one-hidden-layer MLP ``params``
    (w1, b1, w2, b2), each parameter pulled by ``decay`` towards its anchor (None: not pulled):
    zero for training from scratch, the shipped weights for fine-tuning."""
    params = list(params)
    m = [np.zeros_like(p) for p in params]
    v = [np.zeros_like(p) for p in params]
    for step in range(1, epochs + 1):
        if should_stop is not None and step % _STOP_CHECK_EPOCHS == 1 and should_stop():
            raise TrainingStopped("training stopped on request")
        w1, b1, w2, b2 = params
        a1 = np.tanh(xs @ w1 + b1)
        z = (a1 @ w2 + b2)[:, 0]
        prob = 1 / (1 + np.exp(-np.clip(z, -30, 30)))
        dz = (prob - y) * sw / len(y)
        da1 = dz[:, None] @ w2.T * (1 - a1 ** 2)
        grads = [xs.T @ da1, da1.sum(axis=0), a1.T @ dz[:, None], np.array([dz.sum()], dz.dtype)]
        for k, g in enumerate(grads):
            if anchors[k] is not None:
                g = g + decay * (params[k] - anchors[k])
            m[k] = 0.9 * m[k] + 0.1 * g
            v[k] = 0.999 * v[k] + 0.001 * g * g
            mh = m[k] / (1 - 0.9 ** step)
            vh = v[k] / (1 - 0.999 ** step)
            params[k] = params[k] - learning_rate * mh / (np.sqrt(vh) + 1e-8)
    return params


def train_mlp(features: np.ndarray, labels: np.ndarray, hidden: int = 16, epochs: int = 300,
              learning_rate: float = 0.05, positive_weight: float | None = None,
              seed: int = 0, name: str = "candidate_classifier",
              feature_names: tuple[str, ...] = (), dtype=np.float64,
              should_stop: Callable[[], bool] | None = None) -> CandidateClassifier:
    """Full-batch Adam on the weighted cross-entropy; small enough for a few 100k samples.

    ``dtype``: the arithmetic of training (float32 about halves the time; the shipped files were
    trained in float64, which reproduces them). The result is float64 either way.
    ``should_stop``: asked every few epochs; when it says so, :class:`TrainingStopped` is raised,
    so a window closed during a recording's adaptation never waits for the training to end."""
    rng = np.random.default_rng(seed)
    x = np.asarray(features, float)
    y = np.asarray(labels, float)
    mean = x.mean(axis=0)
    scale = x.std(axis=0) + 1e-6
    xs = ((x - mean) / scale).astype(dtype, copy=False)
    if positive_weight is None:
        positive_weight = max((1 - y.mean()) / max(y.mean(), 1e-6), 1.0) ** 0.5
    sw = np.where(y > 0.5, positive_weight, 1.0)
    sw /= sw.mean()
    n_in = x.shape[1]
    params = [rng.normal(0, 1 / np.sqrt(n_in), (n_in, hidden)), np.zeros(hidden),
              rng.normal(0, 1 / np.sqrt(hidden), (hidden, 1)), np.zeros(1)]
    params = [p.astype(dtype, copy=False) for p in params]
    y = y.astype(dtype, copy=False)
    sw = sw.astype(dtype, copy=False)
    # Weight decay towards zero on the two weight matrices (not the biases).
    params = _adam(params, xs, y, sw, epochs, learning_rate, [0.0, None, 0.0, None], 1e-4, should_stop)
    w1, b1, w2, b2 = (p.astype(np.float64, copy=False) for p in params)
    return CandidateClassifier(name, mean, scale, (w1, w2), (b1, b2), tuple(feature_names))


def train_ensemble(features: np.ndarray, labels: np.ndarray, members: int = 3, hidden: int = 16,
                   epochs: int = 300, seed: int = 0, name: str = "candidate_classifier",
                   feature_names: tuple[str, ...] = (), dtype=np.float64,
                   should_stop: Callable[[], bool] | None = None) -> CandidateClassifier:
    """``members`` MLPs from different initial weights, averaged in logit, as one wider MLP.

    Trained on a few clips, one small MLP's ranking of a clip it has not seen swings with its
    random start (TV clips, leave-one-clip-out: the shuttle ranked first in 416–483 of 707
    frames over two starts). The mean of the members' logits is itself an MLP — their hidden
    layers side by side, the output weights divided by ``members`` — so the shipped file and
    ``CandidateClassifier`` stay as they are.
    """
    nets = [train_mlp(features, labels, hidden=hidden, epochs=epochs, seed=seed * 1000 + k, dtype=dtype,
                      name=name, feature_names=feature_names, should_stop=should_stop)
            for k in range(members)]
    first = nets[0]
    return CandidateClassifier(
        name, first.mean, first.scale,
        (np.hstack([n.weights[0] for n in nets]), np.vstack([n.weights[1] for n in nets]) / members),
        (np.concatenate([n.biases[0] for n in nets]), np.mean([n.biases[1] for n in nets], axis=0)),
        tuple(feature_names))


def fine_tune(classifier: CandidateClassifier, features: np.ndarray, targets: np.ndarray,
              epochs: int = 40, learning_rate: float = 1e-3, positive_weight: float | None = None,
              weight_decay: float = 1e-4, name: str | None = None, dtype=np.float32,
              should_stop: Callable[[], bool] | None = None) -> CandidateClassifier:
    """``classifier`` (one hidden layer, as ``train_mlp`` and ``train_ensemble`` write it) trained
    further on ``features`` / ``targets`` (labels or soft probabilities): full-batch Adam from its
    own weights, its standardisation kept.

    Why not train anew: a new court's evidence is a few thousand candidates, while the shipped
    weights learnt from every tuned-on clip; started from random weights, even the shipped
    classifier's own outputs (rehearsed) do not bring that back. A few small steps from its
    weights move it towards the new court and stay near what it knew. ``weight_decay`` pulls
    towards the *starting* weights, not towards zero, for the same reason. Rows are weighted as
    ``train_mlp`` weights them (positives by the square root of the imbalance)."""
    if len(classifier.weights) != 2:
        raise ValueError("fine_tune takes a classifier with one hidden layer")
    xs = ((np.asarray(features, float) - classifier.mean) / classifier.scale).astype(dtype, copy=False)
    y = np.asarray(targets, float)
    if positive_weight is None:
        positive_weight = max((1 - y.mean()) / max(y.mean(), 1e-6), 1.0) ** 0.5
    sw = np.where(y > 0.5, positive_weight, 1.0)
    sw = (sw / sw.mean()).astype(dtype, copy=False)
    y = y.astype(dtype, copy=False)
    start = [classifier.weights[0], classifier.biases[0], classifier.weights[1], classifier.biases[1]]
    start = [np.asarray(p, dtype) for p in start]
    params = [p.copy() for p in start]
    params = _adam(params, xs, y, sw, epochs, learning_rate, start, weight_decay, should_stop)
    w1, b1, w2, b2 = (p.astype(np.float64) for p in params)
    return CandidateClassifier(name or f"{classifier.name} (fine-tuned)", classifier.mean, classifier.scale,
                               (w1, w2), (b1, b2), classifier.feature_names)
