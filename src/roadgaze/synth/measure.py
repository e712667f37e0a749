"""How well the landmark stage and the yaw model recover known yaws on rendered frames."""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from roadgaze.config import Config
from roadgaze.evaluation.stats import RangeStats, range_stats
from roadgaze.synth.clip import DEFAULT_FPS
from roadgaze.synth.renderer import DEFAULT_SIZE, FaceRenderer, load_photo
from roadgaze.types import FloatArray

YAW_RANGES_DEG: tuple[tuple[float, float], ...] = (
    (0.0, 15.0),
    (15.0, 30.0),
    (30.0, 45.0),
    (45.0, 60.0),
)
"""The |true yaw| ranges the measurement reports on; each includes its low end, the last both."""


@dataclass(frozen=True, slots=True)
class YawRecovery:
    """Yaw estimated on a rendered sweep against its truth."""

    truth_deg: FloatArray
    estimate_deg: FloatArray
    """NaN where no face was found or the yaw model could not explain the geometry."""
    ranges: tuple[RangeStats, ...]
    overall: RangeStats
    mesh_estimate_deg: FloatArray
    """The same yaw model on the turned mesh's own landmarks (a perfect landmarker): separates
    the face model's and the mesh's share of the error from the landmarker's."""
    mesh_ranges: tuple[RangeStats, ...]
    mesh_overall: RangeStats
    model: str
    size: tuple[int, int]
    video: bool


def measure_yaw_recovery(
    config: Config | None = None,
    photo: Path | None = None,
    size: tuple[int, int] = DEFAULT_SIZE,
    step_deg: float = 1.0,
    max_yaw_deg: float = 60.0,
    video: bool = True,
    renderer: FaceRenderer | None = None,
) -> YawRecovery:
    """Render a yaw sweep -max..max in `step_deg` steps and estimate each frame's yaw.

    The estimate is the landmark stage (MediaPipe, the configured landmark choice) followed by the
    configured yaw model (Center-CE by default), exactly as the pose stage computes it.
    `video`: run the landmarker in VIDEO mode over the sweep as a 15 fps clip (as the service
    does); False: each still in IMAGE mode.
    """
    from roadgaze.landmarks import MediaPipeLandmarker, features_from_landmarks
    from roadgaze.landmarks.model_store import resolve_model
    from roadgaze.pose import PoseEstimator

    config = config if config is not None else Config()
    renderer = (
        renderer if renderer is not None else FaceRenderer(load_photo(photo), size, config=config)
    )
    count = round(2 * max_yaw_deg / step_deg) + 1
    truth = np.linspace(-max_yaw_deg, max_yaw_deg, count)
    estimate = np.full(count, np.nan)
    mesh_estimate = np.full(count, np.nan)
    model_path = resolve_model(config.model)
    with MediaPipeLandmarker(config.landmarks, model_path, video=video) as detector:
        pose = PoseEstimator.from_config(config)
        for index, yaw_deg in enumerate(truth):
            image = renderer.render(float(yaw_deg))
            detection = detector.detect(image, index / DEFAULT_FPS if video else None)
            value = pose.raw_yaw_deg(detection.driver)
            if value is not None:
                estimate[index] = value
            exact = features_from_landmarks(renderer.turned_points(float(yaw_deg)), renderer.size)
            value = pose.raw_yaw_deg(exact)
            if value is not None:
                mesh_estimate[index] = value
    last = len(YAW_RANGES_DEG) - 1

    def by_range(values: FloatArray) -> tuple[RangeStats, ...]:
        return tuple(
            range_stats(config.geometry.model, truth, values, low, high, i == last)
            for i, (low, high) in enumerate(YAW_RANGES_DEG)
            if low < max_yaw_deg
        )

    return YawRecovery(
        truth_deg=truth,
        estimate_deg=estimate,
        ranges=by_range(estimate),
        overall=range_stats(config.geometry.model, truth, estimate, 0.0, max_yaw_deg, True),
        mesh_estimate_deg=mesh_estimate,
        mesh_ranges=by_range(mesh_estimate),
        mesh_overall=range_stats("mesh", truth, mesh_estimate, 0.0, max_yaw_deg, True),
        model=config.geometry.model,
        size=renderer.size,
        video=video,
    )


def format_measurement(result: YawRecovery) -> str:
    """Per range: frames, detections, MAE, bias, offset and max error, then the same model's MAE
    and bias on the turned mesh's own landmarks."""
    mode = "VIDEO mode sweep" if result.video else "IMAGE mode stills"
    lines = [
        f"yaw recovery on synthetic frames ({result.size[0]}x{result.size[1]}, {mode}, "
        f"model {result.model}); errors are estimate - truth in degrees",
        f"{'|yaw| range':>12} {'frames':>6} {'found':>6} {'MAE':>6} {'bias':>6} {'offset':>7} "
        f"{'max':>6} | {'mesh MAE':>8} {'mesh bias':>9}",
    ]
    rows = zip(
        (*result.ranges, result.overall), (*result.mesh_ranges, result.mesh_overall), strict=True
    )
    for row, mesh_row in rows:
        label = f"{row.low_deg:g}-{row.high_deg:g}"
        item, mesh = row.stats, mesh_row.stats
        lines.append(
            f"{label:>12} {item.n_images:>6} {item.n_valid:>6} {item.mae_deg:>6.2f} "
            f"{item.sign_bias_deg:>+6.2f} {item.bias_deg:>+7.2f} {item.max_deg:>6.2f} | "
            f"{mesh.mae_deg:>8.2f} {mesh.sign_bias_deg:>+9.2f}"
        )
    lines.append(
        "bias: half the difference of the mean errors at positive and negative yaw (< 0: the "
        "magnitude is underestimated); offset: mean error common to both signs; mesh: the same "
        "model on the rendered mesh's exact landmarks (no landmarker error)."
    )
    return "\n".join(lines)


def write_measurement_csv(path: Path, result: YawRecovery) -> None:
    """Rows `truth_yaw_deg,estimate_yaw_deg,error_deg,mesh_estimate_yaw_deg` (empty: none)."""
    with Path(path).open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(("truth_yaw_deg", "estimate_yaw_deg", "error_deg", "mesh_estimate_yaw_deg"))
        rows = zip(result.truth_deg, result.estimate_deg, result.mesh_estimate_deg, strict=True)
        for truth, estimate, mesh in rows:
            found = math.isfinite(estimate)
            writer.writerow(
                (
                    f"{truth:.3f}",
                    f"{estimate:.3f}" if found else "",
                    f"{estimate - truth:.3f}" if found else "",
                    f"{mesh:.3f}" if math.isfinite(mesh) else "",
                )
            )
