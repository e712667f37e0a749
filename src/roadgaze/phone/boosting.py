"""A small gradient-boosted tree classifier in numpy (pure): the phone model's trainer.

Logistic loss, depth-limited regression trees on quantile bins of each feature (the bins fitted
on the training rows), Newton leaf values with an L2 penalty, shrinkage. Deterministic: the same
rows give the same trees. `fit` returns the trees in `roadgaze.phone.model`'s document format.
Small on purpose: a few dozen features, a few thousand rows.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class BoostSettings:
    """The trainer's choices (`scripts/train-phone.py` picks them leaving drivers out)."""

    trees: int = 80
    depth: int = 3
    learning_rate: float = 0.1
    min_leaf: int = 20
    l2: float = 1.0
    bins: int = 32


def _edges(column: FloatArray, bins: int) -> FloatArray:
    """Candidate thresholds: midpoints between distinct quantiles of the column."""
    values = np.unique(np.quantile(column, np.linspace(0, 1, bins + 1)))
    return (values[:-1] + values[1:]) / 2 if values.size > 1 else values[:0]


class _TreeBuilder:
    """One tree, grown on the rows' bin numbers (`binned`: for each row and feature, how many of
    the feature's thresholds lie below its value), every feature's split scored at once."""

    def __init__(
        self,
        x: FloatArray,
        binned: npt.NDArray[np.intp],
        edges: list[FloatArray],
        settings: BoostSettings,
    ) -> None:
        self.x, self.binned, self.edges, self.settings = x, binned, edges, settings
        self.width = max((e.size for e in edges), default=0) + 1
        """Bins per feature in the flat histograms (the widest feature's thresholds + 1)."""
        self.candidate = (
            np.arange(self.width - 1)[None, :] < np.array([e.size for e in edges])[:, None]
        )
        """[feature, threshold]: whether that feature has that threshold."""
        self.offsets = np.arange(len(edges), dtype=np.intp) * self.width
        self.feature: list[int] = []
        self.threshold: list[float] = []
        self.left: list[int] = []
        self.right: list[int] = []
        self.value: list[float] = []

    def _leaf(self, gradient: FloatArray, hessian: FloatArray) -> int:
        self.feature.append(-1)
        self.threshold.append(0.0)
        self.left.append(-1)
        self.right.append(-1)
        value = -gradient.sum() / (hessian.sum() + self.settings.l2)
        self.value.append(float(value) * self.settings.learning_rate)
        return len(self.value) - 1

    def build(self, rows: npt.NDArray[np.intp], g: FloatArray, h: FloatArray, depth: int) -> int:
        settings = self.settings
        if depth == 0 or rows.size < 2 * settings.min_leaf:
            return self._leaf(g[rows], h[rows])
        best = self._best_split(rows, g, h)
        if best is None:
            return self._leaf(g[rows], h[rows])
        feature, threshold = best
        goes_left = self.x[rows, feature] <= threshold
        node = self._leaf(g[rows], h[rows])  # overwritten below as a split
        self.feature[node], self.threshold[node], self.value[node] = feature, threshold, 0.0
        self.left[node] = self.build(rows[goes_left], g, h, depth - 1)
        self.right[node] = self.build(rows[~goes_left], g, h, depth - 1)
        return node

    def _cumulative(
        self, flat: npt.NDArray[np.intp], weights: FloatArray | None
    ) -> npt.NDArray[Any]:
        """Per feature and threshold: the sum of `weights` (None: the count) over the rows at
        or below it."""
        size = len(self.edges) * self.width
        histogram = np.bincount(flat, weights, size).reshape(len(self.edges), self.width)
        cumulative: npt.NDArray[Any] = np.cumsum(histogram, axis=1)[:, :-1]
        return cumulative

    def _best_split(
        self, rows: npt.NDArray[np.intp], g: FloatArray, h: FloatArray
    ) -> tuple[int, float] | None:
        """The (feature, threshold) of the largest gain above zero; ties go to the first feature
        and the lowest threshold."""
        settings = self.settings
        if self.width == 1:
            return None
        g_rows, h_rows = g[rows], h[rows]
        g_total, h_total = g_rows.sum(), h_rows.sum()
        parent = g_total**2 / (h_total + settings.l2)
        features = len(self.edges)
        flat = (self.binned[rows] + self.offsets).ravel()
        g_cum = self._cumulative(flat, np.repeat(g_rows, features))
        h_cum = self._cumulative(flat, np.repeat(h_rows, features))
        n_cum = self._cumulative(flat, None)
        ok = (
            self.candidate & (n_cum >= settings.min_leaf) & (rows.size - n_cum >= settings.min_leaf)
        )
        if not ok.any():
            return None
        gain = (
            g_cum**2 / (h_cum + settings.l2)
            + (g_total - g_cum) ** 2 / (h_total - h_cum + settings.l2)
            - parent
        )
        gain = np.where(ok, gain, -np.inf)
        feature, index = np.unravel_index(int(np.argmax(gain)), gain.shape)
        if not gain[feature, index] > 1e-9:
            return None
        return int(feature), float(self.edges[feature][index])


def fit(x: FloatArray, y: npt.NDArray[np.integer], settings: BoostSettings) -> dict[str, Any]:
    """Trees for labels `y` (0/1) of rows `x`: `{"baseline": ..., "trees": [...]}`."""
    x = np.asarray(x, np.float64)
    labels = np.asarray(y, np.float64)
    rate = float(np.clip(labels.mean(), 1e-3, 1 - 1e-3))
    baseline = float(np.log(rate / (1 - rate)))
    raw = np.full(labels.size, baseline)
    edges = [_edges(x[:, column], settings.bins) for column in range(x.shape[1])]
    binned = np.stack(
        [np.searchsorted(e, x[:, column], side="left") for column, e in enumerate(edges)], axis=1
    ).astype(np.intp)
    trees: list[dict[str, Any]] = []
    rows = np.arange(labels.size)
    for _ in range(settings.trees):
        probability = 1.0 / (1.0 + np.exp(-raw))
        gradient, hessian = probability - labels, probability * (1 - probability)
        builder = _TreeBuilder(x, binned, edges, settings)
        builder.build(rows, gradient, hessian, settings.depth)
        tree = {
            "feature": builder.feature,
            "threshold": [round(value, 6) for value in builder.threshold],
            "left": builder.left,
            "right": builder.right,
            "value": [round(value, 6) for value in builder.value],
        }
        raw += predict_tree(tree, x)
        trees.append(tree)
    return {"baseline": round(baseline, 6), "trees": trees}


def predict_tree(tree: dict[str, Any], x: FloatArray) -> FloatArray:
    """One tree's values for every row of `x` (vectorised)."""
    node = np.zeros(x.shape[0], np.intp)
    feature = np.asarray(tree["feature"], np.intp)
    threshold = np.asarray(tree["threshold"], np.float64)
    left, right = np.asarray(tree["left"], np.intp), np.asarray(tree["right"], np.intp)
    value = np.asarray(tree["value"], np.float64)
    for _ in range(64):
        inner = feature[node] >= 0
        if not inner.any():
            break
        rows = np.flatnonzero(inner)
        here = node[rows]
        goes_left = x[rows, feature[here]] <= threshold[here]
        node[rows] = np.where(goes_left, left[here], right[here])
    values: FloatArray = value[node]
    return values


def predict(document: dict[str, Any], x: FloatArray) -> FloatArray:
    """0..1 scores of every row of `x` (what `PhoneModel.score` gives row by row)."""
    raw = np.full(x.shape[0], float(document["baseline"]))
    for tree in document["trees"]:
        raw += predict_tree(tree, x)
    scores: FloatArray = 1.0 / (1.0 + np.exp(-np.clip(raw, -60, 60)))
    return scores
