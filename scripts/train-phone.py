"""Train the phone classifier shipped as `src/roadgaze/phone/phone_model.json`.

    python scripts/train-phone.py DATA/statefarm-dev [--out PATH] [--features NPZ] [--models lite]

Only the development drivers of the folder are used. Each image goes through the hand stage
(with the upper body) and the face landmarker as stills
(`roadgaze.evaluation.phone.image_features`, the vector the service judges). The trainer's
settings are chosen leaving drivers out (every driver's images scored by a model fitted without
that driver): the candidate with the highest recall at a false-positive rate of 0.10 over all
other classes, ties to the smaller model. The threshold is read from those out-of-fold scores;
the final model is fitted on every development driver.
`--features` caches the feature matrix (re-running on the same images skips the models).
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "src"))

from roadgaze.config import load_config  # noqa: E402
from roadgaze.evaluation.phone import (  # noqa: E402
    Features,
    format_report,
    image_features,
    load_phone_truth,
    out_of_fold_scores,
    score_report,
    threshold_at_fpr,
)
from roadgaze.phone.boosting import BoostSettings, fit  # noqa: E402
from roadgaze.phone.features import FEATURES  # noqa: E402

VERSION = "3"
CANDIDATES = (
    BoostSettings(trees=40, depth=2, learning_rate=0.15),
    BoostSettings(trees=80, depth=3, learning_rate=0.1),
    BoostSettings(trees=150, depth=3, learning_rate=0.08),
)


def features_of(dataset: Path, cache: Path | None, models: str) -> Features:
    truths = load_phone_truth(dataset)
    if cache is not None and cache.is_file():
        with np.load(cache) as stored:
            if list(stored["files"]) == [truth.file for truth in truths]:
                return Features(tuple(truths), stored["x"], stored["judged"])
    config = load_config(environ={})
    config = config.model_copy(update={"hands": config.hands.model_copy(update={"models": models})})
    features = image_features(dataset, truths, config, progress=True)
    if cache is not None:
        np.savez(
            cache,
            files=np.array([t.file for t in truths]),
            x=features.x,
            judged=features.judged,
        )
    return features


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", type=Path)
    parser.add_argument("--out", type=Path, default=REPO / "src/roadgaze/phone/phone_model.json")
    parser.add_argument("--features", type=Path, help="cache of the feature matrix (.npz)")
    parser.add_argument(
        "--models", choices=("lite", "full"), default="lite", help="the hand models (`[hands]`)"
    )
    args = parser.parse_args()
    features = features_of(args.dataset, args.features, args.models)
    best = None
    for settings in CANDIDATES:
        scores = out_of_fold_scores(features, settings)
        threshold = threshold_at_fpr(scores, features.labels)
        report = score_report(features, scores, threshold)
        print(format_report(f"leaving drivers out, {settings}", report), flush=True)
        if best is None or report.recall > best[1].recall + 1e-9:
            best = (settings, report)
    assert best is not None
    settings, report = best
    readable = ~np.isnan(features.x).any(axis=1)
    document = fit(features.x[readable], features.labels[readable], settings)
    drivers = sorted(set(features.groups[readable]))
    model = {
        "version": VERSION,
        "features": list(FEATURES),
        "threshold": round(report.threshold, 6),
        "training": {
            "data": f"{args.dataset.name}: {int(readable.sum())} images of {len(drivers)} "
            "drivers (State Farm distracted-driver development drivers; labels c1-c4 phone use)",
            "drivers": drivers,
            "trainer": "roadgaze.phone.boosting.fit",
            "settings": asdict(settings),
            "chosen_by": "recall at a false-positive rate of 0.10, leaving each driver out",
            "leave_drivers_out": {
                "recall": round(report.recall, 4),
                "fpr": round(report.fpr, 4),
                "per_class": {k: round(v, 4) for k, v in report.per_class.items()},
            },
        },
        **document,
    }
    args.out.write_text(json.dumps(model, separators=(",", ":")) + "\n", encoding="utf-8")
    print(f"wrote {args.out} ({args.out.stat().st_size} bytes): {settings}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
