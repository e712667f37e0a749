"""`roadgaze eval DATASET_DIR`: accuracy of every yaw model, the service's yaw and pitch, and
MediaPipe's own yaw."""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any

from roadgaze.commands.options import PLOT_SUFFIXES, check_output_paths, common_options
from roadgaze.config import Config
from roadgaze.logs import log_written


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "eval",
        parents=[common_options()],
        help="score the yaw models against a data set's ground_truth.csv",
        description="Estimate the pose on every image listed in DATASET_DIR/ground_truth.csv "
        "(columns file,yaw_deg[,pitch_deg][,subject]; rows with |pitch_deg| = 90 are skipped) and "
        "print MAE, RMSE, median error and detection rate per yaw model, for the service's yaw and "
        "for MediaPipe's own yaw, for |yaw| <= 60 deg, for all rows, and MAE and bias per 15 deg "
        "bin; with a subject column also the full-range blend with its constants re-fitted "
        "leaving each subject out; with pitch labels also the pitch's rank correlation and mean "
        "error per tilt and the lap classification (tilt -60 against |tilt| <= 15). Stills take "
        "neutral 0. The report goes "
        "to stdout, the progress bar and the log to stderr.",
    )
    parser.add_argument(
        "dataset",
        type=Path,
        nargs="?",
        metavar="DATASET_DIR",
        help="the folder with ground_truth.csv (default: $ROADGAZE_DATA/pointing04-dev; "
        "`roadgaze data pointing04` builds one from the public archive)",
    )
    parser.add_argument("--report", type=Path, metavar="JSON", help="write all figures as JSON")
    parser.add_argument(
        "--task",
        choices=("pose", "phone"),
        default="pose",
        help="pose (default): the yaw and pitch; phone: phone use on a folder whose "
        "ground_truth.csv has file,phone_use[,class][,subject]: recall and false-positive rate "
        "per class of the shipped classifier, and the same classifier refitted leaving each "
        "driver out (docs/phone.md)",
    )
    parser.add_argument(
        "--predictions", type=Path, metavar="CSV", help="write per-image estimates as CSV"
    )
    parser.add_argument(
        "--plot", type=Path, metavar="PNG", help="plot estimated vs true yaw per model"
    )
    parser.add_argument(
        "--workers",
        type=int,
        default=min(2, os.cpu_count() or 1),
        metavar="N",
        help="worker processes, each with its own landmarker (default: up to 2)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    parser.add_argument(
        "--refit",
        action="store_true",
        help="also fit alpha/beta/gamma globally (all images together) and report beside the "
        "paper's constants; the paper's constants stay the ones used for every other figure",
    )
    parser.add_argument(
        "--compare-landmarks",
        type=Path,
        metavar="MD",
        help="score the candidate landmark choices (docs/landmarks.md) and write a Markdown "
        "table here",
    )
    parser.add_argument(
        "--condition",
        action="append",
        metavar="NAME",
        help="run the condition suite instead: the images with |yaw| <= 60, clean and under "
        "this cabin condition (repeatable, or `all`: ir_grey, dark, glare, motion_blur, jpeg, "
        "low_res, sunglasses, mask; docs/conditions.md), one table row each; NAME:KEY=VALUE,... "
        "sets a condition's parameters, e.g. ir_grey:noise_std=9; with --task phone: the one "
        "condition every image is put under",
    )
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, config: Config) -> int:
    from dataclasses import replace

    from roadgaze.errors import DatasetError
    from roadgaze.evaluation import (
        compare_landmark_choices,
        estimate_images,
        evaluate,
        format_landmark_comparison,
        format_report,
        load_ground_truth,
        refit_constants,
        save_plot,
        write_predictions,
        write_report,
    )
    from roadgaze.evaluation.pointing04 import DATA_ENV, default_dataset
    from roadgaze.landmarks import CANDIDATE_CHOICES
    from roadgaze.landmarks.model_store import resolve_model
    from roadgaze.pose.geometry import FaceModelConstants

    if args.task == "phone":
        from roadgaze.commands.evaluate_phone import run_phone

        if args.dataset is None:
            raise DatasetError("--task phone needs DATASET_DIR (a folder with ground_truth.csv)")
        return run_phone(args, config)
    if args.dataset is None:
        args.dataset = default_dataset()
        if args.dataset is None:
            raise DatasetError(
                f"no DATASET_DIR given and {DATA_ENV} is not set; pass the folder with "
                "ground_truth.csv (`roadgaze data pointing04 SRC OUT` builds one)"
            )
    if args.condition:
        _check_condition_options(args)
    check_output_paths(
        {"DATASET_DIR": args.dataset, "ground_truth.csv": args.dataset / "ground_truth.csv"},
        {
            "--report": args.report,
            "--predictions": args.predictions,
            "--plot": args.plot,
            "--compare-landmarks": args.compare_landmarks,
        },
        {"--plot": PLOT_SUFFIXES},
    )
    truths, skipped = load_ground_truth(args.dataset)
    if not any((args.dataset / truth.file).is_file() for truth in truths):
        raise DatasetError(
            f"none of the {len(truths)} images listed in {args.dataset / 'ground_truth.csv'} "
            f"exists under {args.dataset} (first: {truths[0].file}); check the folder"
        )
    constants = FaceModelConstants.from_config(config.geometry)
    model_path = resolve_model(config.model)
    if args.condition:
        return run_conditions(args, config, truths, model_path)
    jobs = [(args.dataset / truth.file, truth.file) for truth in truths]
    estimates = list(
        estimate_images(
            jobs,
            config.landmarks,
            model_path,
            constants,
            workers=max(1, args.workers),
            progress=not args.no_progress,
            description="eval",
            config=config,
        )
    )
    report = evaluate(str(args.dataset), truths, estimates, skipped, constants)
    if args.refit:
        report = replace(report, refit=refit_constants(truths, estimates, constants))
    print(format_report(report))
    if args.predictions is not None:
        write_predictions(args.predictions, estimates)
        log_written(args.predictions)
    if args.report is not None:
        write_report(args.report, report)
        log_written(args.report)
    if args.plot is not None:
        save_plot(args.plot, truths, estimates)
        log_written(args.plot)
    if args.compare_landmarks is not None:
        table = format_landmark_comparison(
            compare_landmark_choices(truths, estimates, CANDIDATE_CHOICES, constants)
        )
        args.compare_landmarks.parent.mkdir(parents=True, exist_ok=True)
        args.compare_landmarks.write_text(table + "\n", encoding="utf-8")
        print()
        print(table)
        log_written(args.compare_landmarks)
    return 0


def _check_condition_options(args: argparse.Namespace) -> None:
    from roadgaze.errors import ConfigError
    from roadgaze.evaluation.conditions import condition_names

    for flag in ("predictions", "plot", "compare_landmarks"):
        if getattr(args, flag) is not None:
            option = "--" + flag.replace("_", "-")
            raise ConfigError(
                f"{option} is not available with --condition (the suite's report is "
                "the table and --report)"
            )
    if args.refit:
        raise ConfigError("--refit is not available with --condition")
    try:
        condition_names(args.condition)
    except ValueError as exc:
        raise ConfigError(f"--condition: {exc}") from None


def run_conditions(
    args: argparse.Namespace, config: Config, truths: list[Any], model_path: Path
) -> int:
    """The condition suite's table on stdout (and its JSON in `--report`)."""
    import json

    from roadgaze.evaluation.condition_suite import (
        estimate_conditions,
        format_condition_table,
        format_subject_table,
        score_conditions,
        suite_truths,
    )
    from roadgaze.evaluation.conditions import SEED, condition_names

    conditions = condition_names(args.condition)
    rows = suite_truths(truths)
    results = estimate_conditions(
        args.dataset,
        rows,
        conditions,
        config,
        model_path,
        workers=max(1, args.workers),
        progress=not args.no_progress,
    )
    table = score_conditions(conditions, rows, results)
    print(
        f"Condition suite on {args.dataset}: {len(rows)} images with |yaw| <= 60, seed {SEED}, "
        f"landmarks.enhance = {config.landmarks.enhance}"
    )
    print(format_condition_table(table))
    by_subject = format_subject_table(table)
    if by_subject is not None:
        print(f"\n{by_subject}")
    if args.report is not None:
        document = {
            "dataset": str(args.dataset),
            "seed": SEED,
            "enhance": config.landmarks.enhance,
            "conditions": [row.to_json_dict() for row in table],
        }
        args.report.parent.mkdir(parents=True, exist_ok=True)
        args.report.write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")
        log_written(args.report)
    return 0
