"""The phone classifier's trainer: it learns, it is deterministic, and the shipped evaluator
(`PhoneModel.score`) reads its trees exactly as the vectorised `predict` does."""

from __future__ import annotations

import numpy as np
import pytest

from roadgaze.phone.boosting import BoostSettings, fit, predict
from roadgaze.phone.features import FEATURES
from roadgaze.phone.model import PhoneModel


def _data(rows: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(rows, len(FEATURES)))
    y = ((x[:, 0] > 0.3) & (x[:, 5] < 0.5) | (x[:, 9] > 1.2)).astype(int)
    return x, y


def test_fit_learns_an_interaction_and_generalises() -> None:
    x, y = _data(1500, 0)
    document = fit(x, y, BoostSettings(trees=60, depth=3))
    test_x, test_y = _data(1000, 1)
    accuracy = float(((predict(document, test_x) >= 0.5) == test_y).mean())
    assert accuracy > 0.93
    assert fit(x, y, BoostSettings(trees=60, depth=3)) == document  # deterministic


def test_the_shipped_evaluator_equals_the_vectorised_one() -> None:
    x, y = _data(600, 2)
    document = fit(x, y, BoostSettings(trees=20, depth=3))
    model = PhoneModel.from_document(
        {"version": "t", "features": list(FEATURES), "threshold": 0.5, **document}, "test"
    )
    expected = predict(document, x[:50])
    assert [model.score(row) for row in x[:50]] == pytest.approx(list(expected), abs=1e-12)
