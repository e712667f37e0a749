"""`roadgaze eval DATASET_DIR --task phone`: the phone judgement scored on labelled stills."""

from __future__ import annotations

import argparse
import json

import numpy as np

from roadgaze.config import Config
from roadgaze.errors import ConfigError
from roadgaze.evaluation.conditions import CLEAN, parse_condition
from roadgaze.logs import log_written


def run_phone(args: argparse.Namespace, config: Config) -> int:
    """Print the shipped classifier's figures and, with two drivers or more, the figures leaving
    each driver out (the same trainer and settings refitted per fold)."""
    from roadgaze.commands.options import check_output_paths
    from roadgaze.evaluation.phone import (
        format_report,
        image_features,
        load_phone_truth,
        out_of_fold_scores,
        report_json,
        score_report,
        threshold_at_fpr,
    )
    from roadgaze.phone import load_model
    from roadgaze.phone.boosting import BoostSettings

    check_output_paths(
        {"DATASET_DIR": args.dataset, "ground_truth.csv": args.dataset / "ground_truth.csv"},
        {"--report": args.report},
        {},
    )
    condition = _phone_condition(args.condition)
    truths = load_phone_truth(args.dataset)
    model = load_model()
    threshold = (
        model.threshold if config.hands.phone_threshold is None else (config.hands.phone_threshold)
    )
    features = image_features(
        args.dataset, truths, config, progress=not args.no_progress, condition=condition
    )
    scores = np.array([np.nan if np.isnan(row).any() else model.score(row) for row in features.x])
    shipped = score_report(features, scores, threshold)
    document: dict[str, object] = {
        "dataset": str(args.dataset),
        "condition": condition,
        "model": {"version": model.version, "training": model.training},
        "shipped": report_json(shipped),
    }
    under = "" if condition == CLEAN else f" under {condition}"
    print(format_report(f"Phone use on {args.dataset}{under}, shipped classifier", shipped))
    if len(set(features.groups) - {""}) >= 2:
        settings = BoostSettings(**model.training.get("settings", {}))
        held = out_of_fold_scores(features, settings)
        lodo = score_report(features, held, threshold_at_fpr(held, features.labels))
        print()
        print(format_report("Leaving each driver out (refitted per fold, FPR 0.10)", lodo))
        document["leave_drivers_out"] = report_json(lodo)
    if args.report is not None:
        args.report.parent.mkdir(parents=True, exist_ok=True)
        args.report.write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")
        log_written(args.report)
    return 0


def _phone_condition(requested: list[str] | None) -> str:
    """The one condition the images are put under (`clean` without `--condition`); ConfigError
    for more than one, `all`, or an unknown condition or parameter."""
    if not requested:
        return CLEAN
    if len(requested) > 1 or requested[0] == "all":
        raise ConfigError(
            f"--task phone takes one --condition, found {', '.join(requested)}; "
            "run once per condition"
        )
    if requested[0] != CLEAN:
        try:
            parse_condition(requested[0])
        except ValueError as exc:
            raise ConfigError(f"--condition: {exc}") from None
    return requested[0]
