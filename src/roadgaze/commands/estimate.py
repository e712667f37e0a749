"""`roadgaze estimate IMAGE...`: one JSON object per image with every model's yaw."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from roadgaze.commands.options import common_options
from roadgaze.config import Config


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "estimate",
        parents=[common_options()],
        help="estimate the driver's head yaw in still images (one JSON line per image)",
        description="Run MediaPipe and the five yaw models on each image and print one JSON "
        "object per image: file, face, yaw_deg (the service's, full range by default), models, "
        "pitch_deg, pitch_geometric_deg, zone (neutral 0), mediapipe_yaw_deg, "
        "mediapipe_pitch_deg, x_left, x_right, x_center, roll_deg, and the phone judgement: "
        "n_hands, phone_use (null when it cannot judge, or without the hand models: `roadgaze "
        "model fetch hands`), phone_score, phone_hand, phone_pose. Yaw > 0: head turned to the "
        "person's own left; pitch > 0: looking up. An image "
        "that cannot be read gives an object with 'error' and the others are still processed "
        "(exit code 1 if any image could not be read).",
    )
    parser.add_argument("images", nargs="+", type=Path, metavar="IMAGE")
    parser.add_argument(
        "--workers", type=int, default=1, metavar="N", help="worker processes (default 1)"
    )
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.evaluation import estimate_images
    from roadgaze.landmarks.model_store import resolve_model
    from roadgaze.pose.geometry import FaceModelConstants

    constants = FaceModelConstants.from_config(config.geometry)
    model_path = resolve_model(config.model)
    jobs = [(path, str(path)) for path in args.images]
    failures = 0
    phone = PhoneOfImage.from_config(config)
    for estimate in estimate_images(
        jobs, config.landmarks, model_path, constants, workers=max(1, args.workers), config=config
    ):
        fields = estimate.to_json_dict()
        if estimate.error is None:
            fields.update(phone.fields(Path(estimate.file), estimate))
        print(json.dumps(fields), flush=True)
        if estimate.error is not None:
            failures += 1
            print(f"roadgaze estimate: {estimate.error}", file=sys.stderr)
    return 1 if failures else 0


class PhoneOfImage:
    """The phone judgement of a still (`roadgaze.phone`), its fields null without hand models."""

    def __init__(self, stage: Any, model: Any, threshold: float | None) -> None:
        self._stage, self._model, self._threshold = stage, model, threshold

    @classmethod
    def from_config(cls, config: Config) -> PhoneOfImage:
        from roadgaze.landmarks.hands.stage import HandStage
        from roadgaze.phone import load_model

        stage = HandStage.from_config(config)
        return cls(stage, None if stage is None else load_model(), config.hands.phone_threshold)

    def fields(self, path: Path, estimate: Any) -> dict[str, Any]:
        """The phone fields of the image at `path` with its face `estimate`."""
        from roadgaze.evaluation import read_image
        from roadgaze.landmarks.features import finite_box_px
        from roadgaze.outputs.records import hand_fields
        from roadgaze.phone.judge import judge_box

        if self._stage is None:
            return {"n_hands": None, "phone_use": None, "phone_score": None}
        found = self._stage.run(read_image(path), None)
        points = estimate.landmarks_px
        box = None if points is None else finite_box_px(points[:, :2])
        head = (estimate.mediapipe_yaw_deg, estimate.mediapipe_pitch_deg)
        body = found.body_arrays
        verdict = judge_box(found.hands, box, found.size, self._model, self._threshold, head, body)
        fields = hand_fields(found.hands, verdict)
        return {
            key: fields[key]
            for key in ("n_hands", "phone_use", "phone_score", "phone_hand", "phone_pose")
        }
