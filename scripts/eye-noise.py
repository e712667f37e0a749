"""How noisy and how biased MediaPipe's eye direction is on real faces, per axis.

    PYTHONPATH=src python scripts/eye-noise.py [--data $ROADGAZE_DATA] [--json FILE]

The figures behind the eye calibration's thresholds (docs/eyes.md, "Eye direction noise"):

- **Pointing'04 stills** (`DATA/pointing04-dev`, IMAGE mode, the service's head yaw): the eye-in-
  head yaw and pitch of open eyes that give a direction. *Resting direction per subject*: the mean
  of the subject's two frontal stills (pan 0, tilt 0), and its spread over the subjects (what the
  calibration must learn). *Repeatability*: each subject holds every pose twice (two series);
  the standard deviation of the difference of the two readings at the same label, over the labels
  with |pan| <= 45 and |tilt| <= 30, divided by sqrt 2 (one image's noise, including a different
  share of eyes and head in the two series: an upper bound).
- **The shared GIFs** (`DATA/videos`, VIDEO mode, the whole pipeline with the default settings):
  the eye direction on the open-eyed frames with a steady head (|yaw rate| <= 60 deg/s) and the
  head within 20 deg of ahead: mean (the clip's resting direction), standard deviation around it,
  and frame-to-frame noise (standard deviation of the differences / sqrt 2), and the mean pitch
  over every open frame with a direction (a sweeping head included); then what the
  monitor learned (calibration state, noise, thresholds) and on how many frames the calibrated
  eyes moved the gaze off the head pose.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import os
import statistics
import sys
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve()
# The evaluation data: $ROADGAZE_DATA, else the folder beside the checkout (as the tests find it).
DATA = Path(os.environ.get("ROADGAZE_DATA") or HERE.parents[2] / "shared" / "data")
sys.path.insert(0, str(HERE.parents[1] / "src"))

from roadgaze.config import Config  # noqa: E402
from roadgaze.evaluation import load_ground_truth  # noqa: E402
from roadgaze.evaluation.images import StillPose, read_image  # noqa: E402
from roadgaze.landmarks.eyes import driver_eyes  # noqa: E402
from roadgaze.landmarks.landmarker import MediaPipeLandmarker  # noqa: E402
from roadgaze.landmarks.model_store import resolve_model  # noqa: E402
from roadgaze.monitor.eye_calibration import thresholds_deg  # noqa: E402
from roadgaze.pipeline import RunOptions, build_run  # noqa: E402

GIFS = (
    "head-pose-face-detection-male.gif",
    "head-pose-face-detection-female-and-male.gif",
    "head-pose-face-detection-female.gif",
)
STEADY_DPS = 60.0
AHEAD_DEG = 20.0


def _sd(values: list[float]) -> float:
    return statistics.pstdev(values) if len(values) > 1 else math.nan


def stills(dataset: Path, config: Config) -> dict[str, Any]:
    """Resting direction per subject and repeatability on Pointing'04 (see the module doc)."""
    truths, _ = load_ground_truth(dataset)
    still = StillPose.from_config(config)
    readings: dict[tuple[str, int, float, float], tuple[float, float]] = {}
    with MediaPipeLandmarker(config.landmarks, resolve_model(config.model), video=False) as det:
        for truth in truths:
            if abs(truth.yaw_deg) > 45 or truth.pitch_deg is None or abs(truth.pitch_deg) > 30:
                continue
            face = det.detect(read_image(dataset / truth.file)).driver
            if face is None:
                continue
            yaw, _, _ = still.estimate(face)
            eyes = driver_eyes(face, yaw, config.eyes)
            if eyes is None or eyes.yaw_deg is None or eyes.pitch_deg is None:
                continue
            series = int(Path(truth.file).name[8])  # personSSsNN...: subject, series, index
            key = (truth.subject or "", series, truth.yaw_deg, truth.pitch_deg)
            readings[key] = (eyes.yaw_deg, eyes.pitch_deg)
    resting: dict[str, tuple[float, float]] = {}
    for subject in sorted({k[0] for k in readings}, key=lambda s: (len(s), s)):
        frontal = [v for k, v in readings.items() if k[0] == subject and k[2:] == (0.0, 0.0)]
        if frontal:
            resting[subject] = (
                statistics.fmean(v[0] for v in frontal),
                statistics.fmean(v[1] for v in frontal),
            )
    pairs = [
        (readings[k], readings[(k[0], 2, k[2], k[3])])
        for k in readings
        if k[1] == 1 and (k[0], 2, k[2], k[3]) in readings
    ]
    result: dict[str, Any] = {"faces": len(readings), "pairs": len(pairs), "resting": resting}
    for axis, name in ((0, "yaw"), (1, "pitch")):
        values = [v[axis] for v in resting.values()]
        result[f"resting_{name}_range_deg"] = (min(values), max(values))
        result[f"resting_{name}_sd_deg"] = _sd(values)
        diffs = [a[axis] - b[axis] for a, b in pairs]
        result[f"repeat_{name}_sd_deg"] = _sd(diffs) / math.sqrt(2)
    return result


def video(path: Path, config: Config) -> dict[str, Any]:
    """The eye direction over one clip through the whole pipeline (see the module doc)."""
    options = RunOptions(str(path), command="eye-noise", quiet=True)
    with build_run(config, options) as run:
        records = [processed.record for processed in run.frames()]
    pipeline = run.pipeline
    yaws, pitches, any_pitches = [], [], []
    for record in records:
        sample, eyes = record.sample, record.verdict.eyes
        if eyes.status.value == "open" and eyes.eye_pitch_deg is not None:
            any_pitches.append(eyes.eye_pitch_deg)
        steady = sample.yaw_rate_dps is not None and abs(sample.yaw_rate_dps) <= STEADY_DPS
        ahead = sample.yaw_deg is not None and abs(sample.yaw_deg) <= AHEAD_DEG
        judged = eyes.status.value == "open" and not eyes.reason and steady and ahead
        if judged and eyes.eye_yaw_deg is not None and eyes.eye_pitch_deg is not None:
            yaws.append(eyes.eye_yaw_deg)
            pitches.append(eyes.eye_pitch_deg)
    moved = sum(
        1
        for r in records
        if r.verdict.eyes.gaze_source == "eyes"
        and (r.verdict.eyes.gaze_yaw_deg, r.verdict.eyes.gaze_pitch_deg)
        != (r.sample.yaw_deg, r.sample.pitch_deg)
    )
    calibration = pipeline.monitor.state.eyes.calibration
    result: dict[str, Any] = {
        "frames": len(records),
        "steady_ahead_open": len(yaws),
        "calibration": calibration.status().value,
        "learned_noise_deg": calibration.noise_deg(),
        "thresholds_deg": thresholds_deg(config.monitor, calibration),
        "frames_eyes_moved_gaze": moved,
        "open_with_direction": len(any_pitches),
        "pitch_mean_any_deg": statistics.fmean(any_pitches) if any_pitches else math.nan,
        "zones": {z: sum(1 for r in records if r.verdict.zone == z) for z in _zones(records)},
    }
    for name, values in (("yaw", yaws), ("pitch", pitches)):
        result[f"{name}_mean_deg"] = statistics.fmean(values) if values else math.nan
        result[f"{name}_sd_deg"] = _sd(values)
        steps = [b - a for a, b in itertools.pairwise(values)]
        result[f"{name}_frame_noise_deg"] = _sd(steps) / math.sqrt(2) if steps else math.nan
    return result


def _zones(records: list[Any]) -> list[str]:
    return sorted({str(r.verdict.zone) for r in records})


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=DATA)
    parser.add_argument("--json", type=Path, help="also write every figure as JSON")
    args = parser.parse_args()
    config = Config()
    report: dict[str, Any] = {}
    dataset = args.data / "pointing04-dev"
    if (dataset / "ground_truth.csv").is_file():
        s = report["pointing04"] = stills(dataset, config)
        print(f"Pointing'04 stills: {s['faces']} faces with an eye direction, {s['pairs']} pairs")
        for name in ("yaw", "pitch"):
            low, high = s[f"resting_{name}_range_deg"]
            print(
                f"  {name:5}: resting per subject {low:+.1f}..{high:+.1f} deg "
                f"(sd {s[f'resting_{name}_sd_deg']:.1f}), one image's noise "
                f"{s[f'repeat_{name}_sd_deg']:.1f} deg"
            )
    for name in GIFS:
        path = args.data / "videos" / name
        if not path.is_file():
            continue
        v = report[name] = video(path, config)
        print(
            f"{name}: {v['frames']} frames, {v['steady_ahead_open']} open, steady, ahead; "
            f"pitch {v['pitch_mean_any_deg']:+.1f} deg over the {v['open_with_direction']} open "
            "frames with a direction"
        )
        for axis in ("yaw", "pitch"):
            print(
                f"  {axis:5}: mean {v[f'{axis}_mean_deg']:+.1f}, sd {v[f'{axis}_sd_deg']:.1f}, "
                f"frame to frame {v[f'{axis}_frame_noise_deg']:.1f} deg"
            )
        noise, limits = v["learned_noise_deg"], v["thresholds_deg"]
        print(
            f"  monitor: {v['calibration']}, noise {noise[0]:.1f}/{noise[1]:.1f}, thresholds "
            f"{limits[0]:.1f}/{limits[1]:.1f} deg (yaw/pitch); eyes moved the gaze on "
            f"{v['frames_eyes_moved_gaze']} frames; zones {v['zones']}"
        )
    if args.json is not None:
        args.json.write_text(json.dumps(report, indent=1, default=str) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
