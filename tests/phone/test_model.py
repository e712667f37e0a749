"""The shipped phone classifier: small, named, of this roadgaze's features; bad files are one
line."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from roadgaze.errors import ModelError
from roadgaze.phone.features import FEATURES
from roadgaze.phone.model import load_model

SHIPPED = Path(__file__).resolve().parents[2] / "src" / "roadgaze" / "phone" / "phone_model.json"


def test_the_shipped_model_is_small_and_names_its_training() -> None:
    model = load_model()
    assert SHIPPED.stat().st_size < 80_000  # 150 trees of depth 3, as compact JSON
    assert 0.0 < model.threshold < 1.0
    assert model.trees
    assert "State Farm" in model.training["data"]
    assert len(model.training["drivers"]) == 13
    assert model.training["leave_drivers_out"]["fpr"] <= 0.1001


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("not json", "is not JSON"),
        ("[1, 2]", "not an object"),
        ('{"features": ["x"], "version": "1"}', "other features"),
        (json.dumps({"features": list(FEATURES)}), "is not a phone model"),
    ],
)
def test_a_bad_model_file_is_one_line(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "phone.json"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ModelError, match=message) as caught:
        load_model(path)
    assert "\n" not in str(caught.value)
