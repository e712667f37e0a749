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
from typing import Any, Literal, Self

from pydantic import Field, ValidationError, field_validator, model_validator

from roadgaze.config.drowsiness import DrowsinessSettings
from roadgaze.config.eyes import EyeMonitorSettings, EyesConfig
from roadgaze.config.hands import HandsConfig
from roadgaze.config.locations import LocationConfig
from roadgaze.config.notices import NoticeSettings
from roadgaze.config.protocol import ProtocolSettings
from roadgaze.config.record import RecordConfig
from roadgaze.config.section import Section as _Section
from roadgaze.config.support import SupportSettings
from roadgaze.config.zenoh import ZenohConfig
from roadgaze.config.zones import ZoneConfig, check_area1, default_zones, mirrored_zones
from roadgaze.errors import ConfigError

ENV_PREFIX = "ROADGAZE__"


class ModelConfig(_Section):
    """Where the MediaPipe face landmarker model comes from."""

    path: Path | None = None
    """Explicit model file; used first when set (also env ROADGAZE_MODEL_PATH)."""
    cache_dir: Path | None = None
    """Cache folder; default $ROADGAZE_CACHE_DIR, else $XDG_CACHE_HOME/roadgaze."""
    allow_download: bool = True
    """Fetch the model on first use when it is not found locally."""
    download_timeout_s: float = Field(default=60.0, gt=0)


YAW_MODEL_NAMES = ("full_range", "cylindrical", "ellipsoidal", "ce", "center_ce", "boundary_ce")
"""Values of `geometry.model`: the service's full-range yaw, then the paper's five models."""


class GeometryConfig(_Section):
    """The face model turning boundaries and centre into yaw (Narayanan et al. 2014)."""

    model: Literal["full_range", "cylindrical", "ellipsoidal", "ce", "center_ce", "boundary_ce"] = (
        "full_range"
    )
    """`full_range`: Center-CE blended into the cylinder where MediaPipe's own yaw says the head
    is turned beyond Center-CE's range (docs/pose.md); any other value: that paper model alone."""
    alpha: float = Field(default=0.25, ge=0)
    beta: float = Field(default=1.25, gt=1)
    gamma_c: float = Field(default=0.1269, ge=0)
    gamma_b: float = Field(default=0.5774, ge=0)
    full_range_cue_deg: tuple[float, float] = (20.0, 90.0)
    """|MediaPipe matrix yaw| where the full-range blend starts and where it would reach the
    cylinder (smoothstep between)."""

    @field_validator("full_range_cue_deg")
    @classmethod
    def _ordered_cue(cls, value: tuple[float, float]) -> tuple[float, float]:
        if not 0.0 <= value[0] < value[1]:
            raise ValueError(f"needs 0 <= start < end, found {list(value)}")
        return value


class PoseConfig(_Section):
    """Head pitch (docs/pose.md); the yaw model is `[geometry] model`."""

    pitch_model: Literal["matrix", "geometric"] = "matrix"
    """`matrix`: MediaPipe's facial-transformation-matrix pitch with `pitch_down_gain` below the
    neutral (the default, better by measurement); `geometric`: the vertical CE model (P4)."""
    pitch_down_gain: float = Field(default=1.48, ge=1.0, le=3.0)
    """Below the neutral pose the matrix pitch's deviation is multiplied by this (1: off)."""


class LandmarksConfig(_Section):
    """MediaPipe FaceLandmarker settings and how the driver is chosen among several faces."""

    max_faces: int = Field(default=4, ge=1, le=10)
    min_detection_confidence: float = Field(default=0.5, ge=0, le=1)
    min_presence_confidence: float = Field(default=0.5, ge=0, le=1)
    min_tracking_confidence: float = Field(default=0.5, ge=0, le=1)
    driver: Literal["seat", "largest", "left", "right"] = "seat"
    """Which face is the driver: `seat`, the face in the driver's seat for `[monitor] cabin` and
    the camera mounting, then held by identity (docs/landmarks.md); or, frame by frame, the
    largest, or the one on the image's left or right side."""
    multi_face_check_s: float = Field(default=1.0, ge=0)
    """In a stream, how often the one-face landmarker is checked for further faces (seconds);
    0 runs the `max_faces` landmarker on every frame (slower: its face detector then runs on every
    frame). See docs/landmarks.md."""
    mirror_average: bool = False
    """Also run the mirrored image and average the two measurements: exactly mirror-symmetric
    yaw and slightly better accuracy (docs/landmarks.md) for twice the landmarker time."""
    engine: Literal["litert", "mediapipe"] = "litert"
    """What runs the face landmarker's models: `litert` (the three models on LiteRT with
    MediaPipe's graph rebuilt around them, roadgaze.landmarks.engines) or `mediapipe` (its
    FaceLandmarker, the reference). See docs/landmarks.md."""
    threads: int = Field(default=1, ge=1, le=64)
    """LiteRT's thread count per model (the `litert` engine; MediaPipe's API has none)."""
    delegate: str = Field(default="xnnpack", min_length=1)
    """LiteRT's delegate: `xnnpack` (its CPU kernels), `none` (builtin kernels, no delegate) or
    the path of a delegate library, e.g. a vehicle NPU's from `ai-edge-litert-sdk-*`."""
    enhance: Literal["auto", "off", "always"] = "auto"
    """The front end before the detector (roadgaze.landmarks.front_end): `auto` gives dark or
    flat frames a contrast curve and looks again with it when no face is found, `off` passes
    frames as they come, `always` curves every frame (docs/conditions.md)."""


class CaptureConfig(_Section):
    """Camera settings (ignored for files), and the size of a speed track read."""

    width: int = Field(default=640, gt=0)
    height: int = Field(default=480, gt=0)
    fps: float = Field(default=30.0, gt=0)
    fourcc: str = Field(default="MJPG", min_length=4, max_length=4)
    reconnect_initial_s: float = Field(default=0.5, gt=0)
    reconnect_max_s: float = Field(default=10.0, gt=0)
    speed_track_max_rows: int = Field(default=2_000_000, gt=0)
    """Most rows of a speed track read (roadgaze.speed: 16 bytes each); a longer one is refused."""


class SmoothingConfig(_Section):
    """The online smoother of yaw and pitch (constant-velocity Kalman) and the offline RTS pass."""

    measurement_std_deg: float = Field(default=3.0, gt=0)
    """Noise of one raw measurement until it is measured from the series, and the least noise the
    outlier gate assumes."""
    min_measurement_std_deg: float = Field(default=0.2, gt=0)
    """Floor of the measured noise."""
    noise_window: int = Field(default=31, ge=3, le=1000)
    """Residuals (frames) the measured noise is taken over (about 2 s at 15 fps)."""
    min_noise_samples: int = Field(default=8, ge=1)
    """Residuals needed before the measured noise replaces `measurement_std_deg`."""
    acceleration_std_dps2: float = Field(default=300.0, gt=0)
    """White-noise angular acceleration driving the constant-velocity model."""
    clamp_window_s: float = Field(default=0.5, gt=0)
    """The estimate stays within the raw values of the last this many seconds (offline: +-half)."""
    gate_sigma: float = Field(default=4.0, gt=0)
    """Reject a measurement whose innovation exceeds this many standard deviations."""
    max_rejections: int = Field(default=3, ge=1)
    """After this many consecutive rejections, the track is re-initialised on the measurement."""
    reinit_gap_s: float = Field(default=1.5, gt=0)
    """After this long without a face the track is dropped and restarts on the next face."""
    initial_std_deg: float = Field(default=3.0, gt=0)
    initial_rate_std_dps: float = Field(default=60.0, gt=0)

    @model_validator(mode="after")
    def _window_holds_enough(self) -> SmoothingConfig:
        if self.min_noise_samples > self.noise_window:
            raise ValueError(
                f"min_noise_samples ({self.min_noise_samples}) must not exceed noise_window "
                f"({self.noise_window})"
            )
        return self


class MonitorConfig(
    EyeMonitorSettings, DrowsinessSettings, NoticeSettings, ProtocolSettings, SupportSettings
):
    """Inattention monitor thresholds and glance zones (defaults and sources: docs/monitor.md)."""

    road_half_width_deg: float = Field(default=25.0, gt=0)
    """The road zone is left beyond this |yaw - neutral| and entered again within
    `road_half_width_deg - hysteresis_deg`."""
    hysteresis_deg: float = Field(default=5.0, ge=0)
    """Every zone is kept until the angles leave its rectangle grown by this."""
    road_pitch_deg: tuple[float, float] = (-10.0, 15.0)
    """Pitch relative to the neutral within which the road zone is entered (left beyond the
    limits grown by `hysteresis_deg`)."""
    zones: list[ZoneConfig] = Field(default_factory=default_zones, max_length=32)
    """The other zones, in priority order after the road (first match wins; nothing: away)."""
    driving_related_zones: list[str] = Field(
        default_factory=lambda: ["left_mirror", "right_mirror"]
    )
    """Zones whose time counts as off road (VATS, eyes_on_road) but does not run the
    long-distraction timer."""
    driving_glance_max_s: float | None = Field(default=2.0, gt=0)
    """A continuous stay in a driving-related zone this long is a stare, not a glance: it counts as
    distraction from its start (fail-safe: a long look out of the side window is not excused as a
    mirror check); None: never."""
    driving_glance_entry_s: float | None = Field(default=0.5, gt=0)
    """A stay in a driving-related zone pauses the long-distraction timer only while the episode
    has counted less than this outside the road and those zones: a mirror check starts from the
    road, while a reading in a mirror zone after a look elsewhere (a 70 deg look read as 50 deg,
    the face lost between) continues that look; None: every stay pauses it."""
    neutral_yaw_deg: float | None = None
    """Fixed road-ahead yaw; None learns it online from on-road samples."""
    neutral_pitch_deg: float | None = None
    """Fixed road-ahead pitch; None learns it online from on-road samples."""
    neutral_time_constant_s: float = Field(default=60.0, gt=0)
    neutral_limit_deg: float = Field(default=20.0, ge=0)
    neutral_pitch_limit_deg: float = Field(default=20.0, ge=0)
    neutral_max_rate_dps: float | None = Field(default=60.0, gt=0)
    """A head turning faster than this (smoothed yaw rate) is passing through, not looking at
    the road: it teaches neither the neutral pose nor the eye calibration; None: no limit."""
    long_distraction_s: float = Field(default=3.0, gt=0)
    critical_distraction_s: float = Field(default=6.0, gt=0)
    vats_window_s: float = Field(default=30.0, gt=0)
    vats_threshold_s: float = Field(default=10.0, gt=0)
    vats_rearm_s: float = Field(default=2.0, ge=0)
    unavailable_s: float = Field(default=2.0, gt=0)
    turn_away_deg: float | None = Field(default=None, gt=0)
    """A face lost while |yaw - neutral| exceeded this counts as turned away, not unavailable;
    None: a face lost while the head was off road (outside the road zone) is turned away."""
    min_speed_kmh: float = Field(default=20.0, ge=0)
    locations: list[LocationConfig] = Field(default_factory=list, max_length=32)
    """Gaze locations of this cabin where they differ from roadgaze's estimates
    (roadgaze.cabin; each name at most once): where the conformance scenarios look."""
    lean_limit_m: float = Field(default=0.15, gt=0)
    """Body lean: a head moved farther than this sideways or down from its driving place (its
    face's learned image place, roadgaze.cabin) is off road (zone `body_lean`), whatever it
    faces (a large value: never)."""

    @field_validator("road_pitch_deg")
    @classmethod
    def _ordered_pitch(cls, value: tuple[float, float]) -> tuple[float, float]:
        if not value[0] <= value[1]:
            raise ValueError(f"needs [min, max] with min <= max, found {list(value)}")
        return value

    @model_validator(mode="after")
    def _consistent_zones(self) -> MonitorConfig:
        if self.hysteresis_deg >= self.road_half_width_deg:
            raise ValueError(
                f"hysteresis_deg ({self.hysteresis_deg}) must be smaller than "
                f"road_half_width_deg ({self.road_half_width_deg})"
            )
        names = [zone.name for zone in self.zones]
        reserved = sorted({"road", "away", "body_lean"} & set(names))
        if reserved or len(set(names)) != len(names):
            raise ValueError(
                f"zone names must be unique and not 'road', 'away' or 'body_lean', found {names}"
            )
        located = [location.name for location in self.locations]
        if len(set(located)) != len(located):
            raise ValueError(f"each gaze location at most once in locations, found {located}")
        unknown = sorted(set(self.driving_related_zones) - set(names))
        if unknown:
            raise ValueError(
                f"driving_related_zones names zones that are not configured: {unknown} "
                f"(zones: {names})"
            )
        check_area1(self)
        return self

    def effective_zones(self) -> list[ZoneConfig]:
        """The zones in force: as configured, but the (left-hand-drive) defaults mirrored for a
        right-hand-drive cabin."""
        if self.cabin == "rhd" and self.zones == default_zones():
            return mirrored_zones(self.zones)
        return self.zones

    @model_validator(mode="after")
    def _thresholds_agree(self) -> Self:
        """Refuse timings that contradict each other (each message names both fields)."""
        if self.critical_distraction_s < self.long_distraction_s:
            raise ValueError(
                f"critical_distraction_s ({self.critical_distraction_s:g}) must not be below "
                f"long_distraction_s ({self.long_distraction_s:g})"
            )
        if self.vats_threshold_s > self.vats_window_s:
            raise ValueError(
                f"vats_threshold_s ({self.vats_threshold_s:g}) must not exceed vats_window_s "
                f"({self.vats_window_s:g})"
            )
        return self


class LoggingConfig(_Section):
    level: Literal["DEBUG", "INFO", "WARNING", "ERROR"] = "INFO"
    json_format: bool = False


class Config(_Section):
    """The whole roadgaze configuration."""

    model: ModelConfig = ModelConfig()
    geometry: GeometryConfig = GeometryConfig()
    pose: PoseConfig = PoseConfig()
    landmarks: LandmarksConfig = LandmarksConfig()
    eyes: EyesConfig = EyesConfig()
    hands: HandsConfig = HandsConfig()
    capture: CaptureConfig = CaptureConfig()
    smoothing: SmoothingConfig = SmoothingConfig()
    monitor: MonitorConfig = MonitorConfig()
    zenoh: ZenohConfig = ZenohConfig()
    logging: LoggingConfig = LoggingConfig()
    record: RecordConfig = RecordConfig()


def _parse_value(text: str, origin: str) -> Any:
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text
    except ValueError:  # an integer of more than 4300 digits
        raise ConfigError(
            f"{origin}: {text[:20]!r}... ({len(text)} characters) is not a usable value; "
            "integers are limited to 4300 digits"
        ) from None


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
        message = item["msg"] if len(item["msg"]) <= 300 else item["msg"][:300] + "..."
        if isinstance(found, dict):  # a check across fields: the message names them
            problems.append(f"{where}: {message}")
            continue
        text = repr(found)
        text = text if len(text) <= 80 else f"{text[:60]}... ({len(text)} characters)"
        problems.append(f"{where}: {message} (found {text})")
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
        except ValueError:  # an integer of more than 4300 digits
            raise ConfigError(
                f"config file {path}: a value is not usable; integers are limited to 4300 digits"
            ) from None
        origins.append(str(path))
    env = os.environ if environ is None else environ
    for name, text in sorted(env.items()):
        if name.startswith(ENV_PREFIX):
            dotted = name.removeprefix(ENV_PREFIX).lower().replace("__", ".")
            origin = f"environment {name}"
            _set_path(tree, dotted, _parse_value(text, origin), origin)
            origins.append(name)
    for dotted, text in (overrides or {}).items():
        _set_path(tree, dotted, _parse_value(text, f"--set {dotted}"), f"--set {dotted}")
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
