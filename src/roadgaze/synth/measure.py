"""How well the landmark stage and the pose models recover known poses on rendered frames:
yaw on a yaw sweep, pitch and zones on a yaw x pitch grid."""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

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
    (60.0, 80.0),
)
"""The |true yaw| ranges the measurement reports on, those below the sweep's limit; each includes
its low end, the last one reported both."""


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
    from roadgaze.landmarks import Landmarker, features_from_landmarks
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
    with Landmarker(config.landmarks, model_path, video=video) as detector:
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
    reported = [(low, high) for low, high in YAW_RANGES_DEG if low < max_yaw_deg]
    last = len(reported) - 1

    def by_range(values: FloatArray) -> tuple[RangeStats, ...]:
        return tuple(
            range_stats(config.geometry.model, truth, values, low, high, i == last)
            for i, (low, high) in enumerate(reported)
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


PITCH_RANGES_DEG: tuple[tuple[float, float], ...] = (
    (0.0, 10.0),
    (10.0, 20.0),
    (20.0, 30.0),
    (30.0, 40.0),
)
"""The |true pitch| ranges pitch errors are reported on; the last includes its high end."""

PITCH_ESTIMATORS: tuple[str, ...] = ("service", "matrix", "geometric")
"""`service`: the configured pitch (by default MediaPipe's matrix pitch with the down gain below
the neutral); `matrix`: the matrix pitch alone; `geometric`: the vertical CE model (P4)."""


@dataclass(frozen=True, slots=True)
class PitchRecovery:
    """Pitch and zones estimated on a rendered yaw x pitch grid of stills against the truth.

    Every estimate is relative to the same estimator's value on the frontal still (yaw 0,
    pitch 0), as a stream's learned neutral makes it.
    """

    truth_yaw_deg: FloatArray
    truth_pitch_deg: FloatArray
    found: npt.NDArray[np.bool_]
    pitch_deg: Mapping[str, FloatArray]
    """Estimator name -> pitch relative to its neutral; NaN where no face was found."""
    yaw_deg: FloatArray
    """The configured yaw relative to the frontal still's."""
    truth_zone: tuple[str, ...]
    zone: tuple[str | None, ...]
    """The zone of the estimate (None without a face), both judged as first samples."""
    size: tuple[int, int]

    def ranges(self, estimator: str, max_abs_yaw_deg: float) -> tuple[RangeStats, ...]:
        """Errors per |true pitch| range over the stills with |true yaw| <= `max_abs_yaw_deg`."""
        inside = np.abs(self.truth_yaw_deg) <= max_abs_yaw_deg + 1e-9
        truth = self.truth_pitch_deg[inside]
        estimate = self.pitch_deg[estimator][inside]
        bounds = (*PITCH_RANGES_DEG, (0.0, PITCH_RANGES_DEG[-1][1]))
        last = len(PITCH_RANGES_DEG) - 1
        return tuple(
            range_stats(estimator, truth, estimate, low, high, i >= last)
            for i, (low, high) in enumerate(bounds)
        )


def _grid(step_deg: float, limit_deg: float) -> FloatArray:
    count = round(2 * limit_deg / step_deg) + 1
    return np.linspace(-limit_deg, limit_deg, count)


def measure_pitch_recovery(
    config: Config | None = None,
    photo: Path | None = None,
    size: tuple[int, int] = DEFAULT_SIZE,
    yaw_step_deg: float = 15.0,
    max_yaw_deg: float = 60.0,
    pitch_step_deg: float = 5.0,
    max_pitch_deg: float = 40.0,
    renderer: FaceRenderer | None = None,
) -> PitchRecovery:
    """Render a yaw x pitch grid of stills (the head nods, then turns) and estimate each one.

    The landmark stage runs in IMAGE mode; the pose stage's raw yaw and pitch models and the
    zone classifier run on each still exactly as the service computes them, relative to the
    frontal still. Raises ModelError when the landmarker model is unavailable.
    """
    from roadgaze.landmarks import Landmarker
    from roadgaze.landmarks.model_store import resolve_model
    from roadgaze.monitor.zones import ZoneMap
    from roadgaze.pose import PoseEstimator, head_pitch_deg, midline_pitch_deg

    config = config if config is not None else Config()
    renderer = (
        renderer if renderer is not None else FaceRenderer(load_photo(photo), size, config=config)
    )
    yaws, pitches = _grid(yaw_step_deg, max_yaw_deg), _grid(pitch_step_deg, max_pitch_deg)
    truth = np.array([(yaw, pitch) for yaw in yaws for pitch in pitches]).reshape(-1, 2)
    count = len(truth)
    matrix = np.full(count, np.nan)
    geometric = np.full(count, np.nan)
    yaw = np.full(count, np.nan)
    pose = PoseEstimator.from_config(config)
    with Landmarker(config.landmarks, resolve_model(config.model)) as detector:
        for index, (yaw_deg, pitch_deg) in enumerate(truth):
            face = detector.detect(renderer.render(float(yaw_deg), float(pitch_deg))).driver
            if face is None:
                continue
            yaw[index] = _nan_for_none(pose.raw_yaw_deg(face))
            matrix[index] = _nan_for_none(face.mediapipe_pitch_deg)
            if None not in (face.y_top_px, face.y_bottom_px, face.y_center_px):
                geometric[index] = midline_pitch_deg(
                    face.y_top_px, face.y_bottom_px, face.y_center_px
                )
    frontal = int(np.flatnonzero((truth[:, 0] == 0.0) & (truth[:, 1] == 0.0))[0])
    gain = config.pose.pitch_down_gain
    relative = {
        "matrix": matrix - matrix[frontal],
        "geometric": geometric - geometric[frontal],
        "service": head_pitch_deg(matrix, matrix[frontal], gain) - matrix[frontal],
    }
    if config.pose.pitch_model == "geometric":
        relative["service"] = relative["geometric"]
    yaw_relative = yaw - yaw[frontal]
    zones = ZoneMap.from_config(config.monitor)
    found = np.isfinite(yaw_relative)
    return PitchRecovery(
        truth_yaw_deg=truth[:, 0],
        truth_pitch_deg=truth[:, 1],
        found=found,
        pitch_deg=relative,
        yaw_deg=yaw_relative,
        truth_zone=tuple(zones.classify(float(a), float(b), None) for a, b in truth),
        zone=tuple(
            zones.classify(float(a), 0.0 if np.isnan(b) else float(b), None) if ok else None
            for a, b, ok in zip(yaw_relative, relative["service"], found, strict=True)
        ),
        size=renderer.size,
    )


def _nan_for_none(value: float | None) -> float:
    return math.nan if value is None else float(value)


def zone_agreement(truth: Sequence[str], estimate: Sequence[str | None]) -> list[str]:
    """Lines: overall agreement and, per true zone, how often the estimate names it (and what
    it names instead), over the frames with an estimate."""
    pairs = [(t, e) for t, e in zip(truth, estimate, strict=True) if e is not None]
    if not pairs:
        return ["zones: no frame with a face"]
    agree = sum(t == e for t, e in pairs)
    lines = [
        f"zone agreement {100.0 * agree / len(pairs):.1f} % of {len(pairs)} frames with a face"
    ]
    for zone in sorted({t for t, _ in pairs}):
        named = [e for t, e in pairs if t == zone]
        others = sorted({e for e in named if e != zone and e is not None})
        wrong = ", ".join(f"{o} {sum(e == o for e in named)}" for o in others)
        lines.append(
            f"  {zone:<13} {sum(e == zone for e in named):>4} / {len(named):<4}"
            + (f" (else: {wrong})" if wrong else "")
        )
    return lines


def format_pitch_measurement(result: PitchRecovery) -> str:
    """Per |pitch| range and estimator: MAE and bias, over all yaws and over |yaw| <= 30; then
    the zones against the zones of the truth."""
    lines = [
        f"pitch recovery on synthetic stills ({result.size[0]}x{result.size[1]}, IMAGE mode, "
        f"{int(result.found.sum())} of {len(result.found)} with a face); error = estimate - truth "
        "in degrees, each estimator relative to its own value on the frontal still",
    ]
    for max_yaw in (float(np.max(np.abs(result.truth_yaw_deg))), 30.0):
        lines.append(f"|yaw| <= {max_yaw:g}:")
        lines.append(
            f"  {'estimator':<10}"
            + "".join(f" {f'{lo:g}-{hi:g}':>12}" for lo, hi in PITCH_RANGES_DEG)
            + f" {'all':>12}"
        )
        for estimator in PITCH_ESTIMATORS:
            cells = "".join(
                f" {s.stats.mae_deg:5.2f}/{s.stats.bias_deg:+6.2f}"
                for s in result.ranges(estimator, max_yaw)
            )
            lines.append(f"  {estimator:<10}{cells}")
    lines.append(
        "cells: MAE/mean error; service = the configured pitch (default: matrix, down gain)"
    )
    lines.extend(zone_agreement(result.truth_zone, result.zone))
    return "\n".join(lines)
