"""The shipped phone classifier: a small gradient-boosted tree ensemble read from JSON (pure:
numpy only).

`phone_model.json` (package data, a few kB) holds: `version`, `features` (must equal
`roadgaze.phone.features.FEATURES`), `training` (the data it was fitted on and how, by
`scripts/train-phone.py`), `threshold` (the operating point chosen leaving drivers out),
`baseline` and `trees`: per tree, flat node lists `feature`, `threshold`, `left`, `right`,
`value` and optionally `missing_left` (NaN goes left unless it says otherwise; a leaf has
feature -1; a value at or below a node's threshold goes left). The leaves' values are added
to the baseline; the score is the logistic of the sum.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.errors import ModelError
from roadgaze.phone.features import FEATURES

MODEL_RESOURCE = "phone_model.json"


@dataclass(frozen=True, slots=True)
class Tree:
    feature: tuple[int, ...]
    threshold: tuple[float, ...]
    left: tuple[int, ...]
    right: tuple[int, ...]
    value: tuple[float, ...]
    missing_left: tuple[bool, ...]

    def predict(self, values: npt.NDArray[np.float64]) -> float:
        node = 0
        while self.feature[node] >= 0:
            value = values[self.feature[node]]
            if math.isnan(value):
                go_left = self.missing_left[node]
            else:
                go_left = value <= self.threshold[node]
            node = self.left[node] if go_left else self.right[node]
        return self.value[node]


@dataclass(frozen=True, slots=True)
class PhoneModel:
    """The classifier (see the module docstring)."""

    version: str
    threshold: float
    baseline: float
    trees: tuple[Tree, ...]
    training: dict[str, Any]

    def score(self, values: npt.NDArray[np.float64]) -> float:
        """0..1: how likely the frame with these `FEATURES` values shows phone use."""
        total = self.baseline + sum(tree.predict(values) for tree in self.trees)
        return 1.0 / (1.0 + math.exp(-max(-60.0, min(60.0, total))))

    @classmethod
    def from_document(cls, document: dict[str, Any], origin: str) -> PhoneModel:
        """ModelError (one line naming `origin`) when the document is not a phone model of
        this roadgaze's features."""
        try:
            if tuple(document["features"]) != FEATURES:
                raise ModelError(
                    f"{origin} was trained on other features than this roadgaze computes; "
                    "retrain it with scripts/train-phone.py"
                )
            trees = tuple(
                Tree(
                    tuple(int(n) for n in tree["feature"]),
                    tuple(float(n) for n in tree["threshold"]),
                    tuple(int(n) for n in tree["left"]),
                    tuple(int(n) for n in tree["right"]),
                    tuple(float(n) for n in tree["value"]),
                    tuple(bool(n) for n in tree.get("missing_left", [True] * len(tree["value"]))),
                )
                for tree in document["trees"]
            )
            return cls(
                str(document["version"]),
                float(document["threshold"]),
                float(document["baseline"]),
                trees,
                dict(document.get("training", {})),
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise ModelError(f"{origin} is not a phone model ({exc!r})") from None


def load_model(path: Path | None = None) -> PhoneModel:
    """The shipped classifier, or the one at `path`; ModelError (one line) when unreadable."""
    origin = f"roadgaze/phone/{MODEL_RESOURCE}" if path is None else str(path)
    try:
        if path is None:
            text = resources.files("roadgaze.phone").joinpath(MODEL_RESOURCE).read_text("utf-8")
        else:
            text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ModelError(
            f"cannot read the phone model {origin}: {exc.strerror or exc}; reinstall roadgaze"
        ) from None
    try:
        document = json.loads(text)
    except ValueError as exc:
        raise ModelError(f"{origin} is not JSON ({exc})") from None
    if not isinstance(document, dict):
        raise ModelError(f"{origin} is not a phone model (not an object)")
    return PhoneModel.from_document(document, origin)
