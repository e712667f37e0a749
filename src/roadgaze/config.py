"""Configuration: pydantic models, loaded from a TOML file, then environment, then command line.

Precedence (later wins): built-in defaults < `--config FILE` (TOML, see `config/roadgaze.toml`)
< environment variables `ROADGAZE__<SECTION>__<FIELD>` (e.g. `ROADGAZE__MONITOR__MIN_SPEED_KMH=30`)
< command-line overrides `--set section.field=value`. Values from the environment and `--set` are
parsed as TOML values when they parse (numbers, booleans, arrays) and taken as strings otherwise.
Any bad value raises `ConfigError` naming the field, the value found and what is allowed.
"""

from __future__ import annotations

import os
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from roadgaze.errors import ConfigError

if TYPE_CHECKING:
    from roadgaze.pose.geometry import FaceModelConstants

ENV_PREFIX = "ROADGAZE__"


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class ModelConfig(_Section):
    """Where the MediaPipe face landmarker model comes from."""

    path: Path | None = None
    """Explicit model file; used first when set (also env ROADGAZE_MODEL_PATH)."""
    cache_dir: Path | None = None
    """Cache folder; default $ROADGAZE_CACHE_DIR, else $XDG_CACHE_HOME/roadgaze."""
    allow_download: bool = True
    """Fetch the model on first use when it is not found locally."""
    download_timeout_s: float = Field(default=60.0, gt=0)


class GeometryConfig(_Section):
    """The face model turning boundaries and centre into yaw (Narayanan et al. 2014)."""

    model: Literal["cylindrical", "ellipsoidal", "ce", "center_ce", "boundary_ce"] = "center_ce"
    alpha: float = Field(default=0.25, ge=0)
    beta: float = Field(default=1.25, gt=1)
    gamma_c: float = Field(default=0.1269, ge=0)
    gamma_b: float = Field(default=0.5774, ge=0)

    def face_constants(self) -> FaceModelConstants:
        """The constants as the yaw models take them."""
        from roadgaze.pose.geometry import FaceModelConstants

        return FaceModelConstants(self.alpha, self.beta, self.gamma_c, self.gamma_b)


class LandmarksConfig(_Section):
    """MediaPipe FaceLandmarker settings and how the driver is chosen among several faces."""

    max_faces: int = Field(default=4, ge=1, le=10)
    min_detection_confidence: float = Field(default=0.5, ge=0, le=1)
    min_presence_confidence: float = Field(default=0.5, ge=0, le=1)
    min_tracking_confidence: float = Field(default=0.5, ge=0, le=1)
    driver: Literal["largest", "left", "right"] = "largest"
    """Which face is the driver: the largest, or the one on the image's left or right side."""
    mirror_average: bool = False
    """Also run the mirrored image and average the two measurements: exactly mirror-symmetric
    yaw and slightly better accuracy (docs/landmarks.md) for twice the landmarker time."""


class CaptureConfig(_Section):
    """Camera settings (ignored for files)."""

    width: int = Field(default=640, gt=0)
    height: int = Field(default=480, gt=0)
    fps: float = Field(default=30.0, gt=0)
    fourcc: str = Field(default="MJPG", min_length=4, max_length=4)
    reconnect_initial_s: float = Field(default=0.5, gt=0)
    reconnect_max_s: float = Field(default=10.0, gt=0)


class SmoothingConfig(_Section):
    """Constant-velocity Kalman smoother of yaw."""

    measurement_std_deg: float = Field(default=3.0, gt=0)
    """Standard deviation of one raw Center-CE measurement."""
    acceleration_std_dps2: float = Field(default=200.0, gt=0)
    """White-noise yaw acceleration driving the constant-velocity model."""
    gate_sigma: float = Field(default=4.0, gt=0)
    """Reject a measurement whose innovation exceeds this many standard deviations."""
    max_rejections: int = Field(default=3, ge=1)
    """After this many consecutive rejections, the track is re-initialised on the measurement."""
    reinit_gap_s: float = Field(default=1.5, gt=0)
    """After this long without a face the track is dropped and restarts on the next face."""
    initial_std_deg: float = Field(default=3.0, gt=0)
    initial_rate_std_dps: float = Field(default=60.0, gt=0)


class EyesConfig(_Section):
    """Eye measurement: which eyes are trusted and where their direction comes from.

    Defaults and their sources: docs/eyes.md.
    """

    method: Literal["blendshapes", "iris"] = "blendshapes"
    """Eye-in-head direction from MediaPipe's eyeLook* blendshapes, or from the iris landmarks
    with an eyeball-centre model (a diagnostic: worse on real faces)."""
    max_head_yaw_deg: float = Field(default=60.0, gt=0, le=90)
    """Beyond this head yaw the eyes give no direction (the yaw model saturates)."""
    closure_max_head_yaw_deg: float = Field(default=80.0, gt=0, le=90)
    """Up to this head yaw the nearer eye's openness is still judged."""
    far_eye_max_yaw_deg: float = Field(default=35.0, ge=0, le=90)
    """Beyond this head yaw only the nearer eye is used."""
    far_eye_min_width_ratio: float = Field(default=0.6, ge=0, le=1)
    """An eye narrower than this fraction of the other in the image is not used."""
    min_eye_width_px: float = Field(default=8.0, ge=0)
    min_quality: float = Field(default=0.3, ge=0, le=1)
    """Faces of lower landmark quality (small, cut by the image edge) give no eyes."""
    min_contrast: float = Field(default=0.15, ge=0)
    """Eyes whose opening shows less contrast than this (relative to the skin below) while the
    lids look open are taken as hidden (sunglasses); 0 turns the image check off."""
    occluded_min_openness: float = Field(default=0.18, ge=0)
    """The lids look open (so low contrast means a lens, not a closed lid) above this openness."""


class MonitorConfig(_Section):
    """Inattention monitor thresholds (defaults and their sources: docs/monitor.md)."""

    road_half_width_deg: float = Field(default=25.0, gt=0)
    hysteresis_deg: float = Field(default=5.0, ge=0)
    neutral_yaw_deg: float | None = None
    """Fixed road-ahead yaw; None learns it online from on-road samples."""
    neutral_time_constant_s: float = Field(default=60.0, gt=0)
    neutral_limit_deg: float = Field(default=20.0, ge=0)
    long_distraction_s: float = Field(default=3.0, gt=0)
    critical_distraction_s: float = Field(default=6.0, gt=0)
    vats_window_s: float = Field(default=30.0, gt=0)
    vats_threshold_s: float = Field(default=10.0, gt=0)
    vats_rearm_s: float = Field(default=2.0, ge=0)
    unavailable_s: float = Field(default=2.0, gt=0)
    turn_away_deg: float | None = Field(default=None, gt=0)
    """A face lost while |yaw - neutral| exceeded this counts as turned away, not unavailable;
    None: a face lost while the head was off road (past the road-ahead limit) is turned away."""
    min_speed_kmh: float = Field(default=20.0, ge=0)
    # Eyes: closure, PERCLOS, blinks, gaze (docs/monitor.md, "Eyes").
    eyes_close_below: float = Field(default=0.14, gt=0)
    """Openness (lid gap / eye width) below which the eyes count as closed when the blink score
    agrees (`eyes_blink_min`)."""
    eyes_hard_close_below: float = Field(default=0.10, gt=0)
    """Openness below which the eyes count as closed whatever the blink score."""
    eyes_open_above: float = Field(default=0.18, gt=0)
    """Closed eyes count as open again only above this openness (hysteresis)."""
    eyes_blink_min: float = Field(default=0.4, ge=0, le=1)
    """The eyeBlink score that must agree between `eyes_hard_close_below` and `eyes_close_below`."""
    look_down_head_deg: float = Field(default=8.0, gt=0)
    """Narrowed lids with the head this far below its road pitch (MediaPipe matrix pitch) read
    as looking down, not as closed."""
    gaze_deadband_deg: float = Field(default=10.0, ge=0)
    """Eye-in-head deviations from the driver's resting eye direction below this count as none."""
    eye_neutral_limit_deg: float = Field(default=15.0, ge=0)
    microsleep_s: float = Field(default=1.0, gt=0)
    sleep_s: float = Field(default=3.0, gt=0)
    unresponsive_closed_s: float = Field(default=6.0, gt=0)
    unresponsive_away_s: float = Field(default=6.0, gt=0)
    unresponsive_after_warning_s: float = Field(default=3.0, gt=0)
    closure_gap_s: float = Field(default=0.3, ge=0)
    """Eyes unavailable this long inside a closure do not end it."""
    perclos_window_s: float = Field(default=60.0, gt=0)
    perclos_min_judged_s: float = Field(default=30.0, ge=0)
    """PERCLOS is reported (and may raise `drowsy`) once this much of its window was judged."""
    perclos_drowsy: float = Field(default=0.15, gt=0, le=1)
    perclos_rearm: float = Field(default=0.10, ge=0, le=1)
    long_blink_s: float = Field(default=0.5, gt=0)
    long_blinks_drowsy: int = Field(default=3, ge=1)
    degraded_after_s: float = Field(default=10.0, gt=0)
    """Eyes unavailable this long while moving: monitoring is degraded (head pose only)."""


class ZenohConfig(_Section):
    """Zenoh session and key expressions. Safe defaults: loopback only, no multicast scouting."""

    mode: Literal["peer", "client"] = "peer"
    connect: list[str] = Field(default_factory=list)
    listen: list[str] = Field(default_factory=lambda: ["tcp/127.0.0.1:0"])
    multicast_scouting: bool = False
    config_file: Path | None = None
    """A Zenoh JSON5 config file; when set it is the base and the fields above override it."""
    vehicle_id: str = Field(default="car-0", pattern=r"^[A-Za-z0-9_.-]+$")
    prefix: str = "vehicle/{vehicle_id}/dms"
    speed_key: str = "vehicle/{vehicle_id}/speed"
    """Key expression of the speed input; '' for none. Without a (fresh) speed: taken as moving."""
    speed_stale_s: float = Field(default=5.0, gt=0)
    """A speed older than this (wall time) is forgotten and the vehicle taken as moving again."""
    reconnect_initial_s: float = Field(default=0.5, gt=0)
    """First delay before re-opening a session that could not be opened (client mode)."""
    reconnect_max_s: float = Field(default=10.0, gt=0)


class LoggingConfig(_Section):
    level: Literal["DEBUG", "INFO", "WARNING", "ERROR"] = "INFO"
    json_format: bool = False


class Config(_Section):
    """The whole roadgaze configuration."""

    model: ModelConfig = ModelConfig()
    geometry: GeometryConfig = GeometryConfig()
    landmarks: LandmarksConfig = LandmarksConfig()
    eyes: EyesConfig = EyesConfig()
    capture: CaptureConfig = CaptureConfig()
    smoothing: SmoothingConfig = SmoothingConfig()
    monitor: MonitorConfig = MonitorConfig()
    zenoh: ZenohConfig = ZenohConfig()
    logging: LoggingConfig = LoggingConfig()


def _parse_value(text: str) -> Any:
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def _set_path(tree: dict[str, Any], dotted: str, value: Any, origin: str) -> None:
    parts = dotted.split(".")
    if len(parts) != 2 or not all(parts):
        raise ConfigError(f"{origin}: expected 'section.field', found '{dotted}'")
    section, field = parts
    if section not in Config.model_fields:
        allowed = ", ".join(Config.model_fields)
        raise ConfigError(f"{origin}: unknown section '{section}' (sections: {allowed})")
    node = tree.setdefault(section, {})
    if not isinstance(node, dict):
        raise ConfigError(f"{origin}: '{section}' must be a table")
    node[field] = value


def _format_validation_error(error: ValidationError, origin: str) -> str:
    problems = []
    for item in error.errors():
        where = ".".join(str(p) for p in item["loc"])
        found = item.get("input")
        problems.append(f"{where}: {item['msg']} (found {found!r})")
    return f"bad configuration from {origin}: " + "; ".join(problems)


def load_config(
    path: Path | None = None,
    overrides: Mapping[str, str] | None = None,
    environ: Mapping[str, str] | None = None,
) -> Config:
    """Build the configuration from defaults, a TOML file, the environment and overrides.

    `overrides` maps 'section.field' to a value text as given on the command line. Raises
    `ConfigError` for an unreadable file, unknown keys and out-of-range values.
    """
    tree: dict[str, Any] = {}
    origins = ["defaults"]
    if path is not None:
        try:
            tree = tomllib.loads(Path(path).read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise ConfigError(f"config file {path} not found; pass an existing TOML file") from None
        except (OSError, UnicodeDecodeError) as exc:
            raise ConfigError(f"cannot read config file {path}: {exc}") from None
        except tomllib.TOMLDecodeError as exc:
            raise ConfigError(f"config file {path} is not valid TOML: {exc}") from None
        origins.append(str(path))
    env = os.environ if environ is None else environ
    for name, text in sorted(env.items()):
        if name.startswith(ENV_PREFIX):
            dotted = name.removeprefix(ENV_PREFIX).lower().replace("__", ".")
            _set_path(tree, dotted, _parse_value(text), f"environment {name}")
            origins.append(name)
    for dotted, text in (overrides or {}).items():
        _set_path(tree, dotted, _parse_value(text), f"--set {dotted}")
        origins.append(f"--set {dotted}")
    try:
        return Config.model_validate(tree)
    except ValidationError as exc:
        raise ConfigError(_format_validation_error(exc, ", ".join(origins))) from None


def parse_overrides(items: list[str] | None) -> dict[str, str]:
    """Turn ['section.field=value', ...] from `--set` into a mapping; raises ConfigError."""
    result: dict[str, str] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ConfigError(f"--set expects section.field=value, found '{item}'")
        result[key.strip()] = value.strip()
    return result
