"""Configuration: pydantic models, loaded from a TOML file, then environment, then command line.

Precedence (later wins): built-in defaults < `--config FILE` (TOML, see `config/roadgaze.toml`)
< environment variables `ROADGAZE__<SECTION>__<FIELD>` (e.g. `ROADGAZE__MONITOR__MIN_SPEED_KMH=30`)
< command-line overrides `--set section.field=value`. Values from the environment and `--set` are
parsed as TOML values when they parse (numbers, booleans, arrays) and taken as strings otherwise.
Any bad value raises `ConfigError` naming the field, the value found and what is allowed.
"""

from __future__ import annotations

import os
import re
import tomllib
import typing
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, Self

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)

from roadgaze.errors import ConfigError

if TYPE_CHECKING:
    from roadgaze.pose.geometry import FaceModelConstants

ENV_PREFIX = "ROADGAZE__"
VEHICLE_ID_PATTERN = r"^[A-Za-z0-9_-]{1,64}$"
"""Vehicle ids: letters, digits, '_' and '-', at most 64 (no wildcard, no '/', no empty id)."""
KEY_MAX_CHARS = 1024
"""Longest key expression roadgaze accepts (Zenoh panics on keys over about 64 KiB)."""
_KEY_CHUNK = re.compile(r"[A-Za-z0-9_.~+=%,:;!'()\[\]-]+")


class _Section(BaseModel):
    """A configuration section: unknown keys, non-finite numbers and booleans given for numbers
    are errors."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    @field_validator("*", mode="before")
    @classmethod
    def _no_boolean_for_a_number(cls, value: Any, info: ValidationInfo) -> Any:
        if isinstance(value, bool) and info.field_name is not None:
            annotation = cls.model_fields[info.field_name].annotation
            if annotation is not bool and bool not in typing.get_args(annotation):
                raise ValueError("expected a value of the field's type, found a boolean")
        return value


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

    @model_validator(mode="after")
    def _thresholds_agree(self) -> Self:
        """Refuse thresholds that contradict each other (each message names both fields)."""
        if self.critical_distraction_s < self.long_distraction_s:
            raise ValueError(
                f"critical_distraction_s ({self.critical_distraction_s:g}) must not be below "
                f"long_distraction_s ({self.long_distraction_s:g})"
            )
        if self.hysteresis_deg >= self.road_half_width_deg:
            raise ValueError(
                f"hysteresis_deg ({self.hysteresis_deg:g}) must be below road_half_width_deg "
                f"({self.road_half_width_deg:g}): the head could never count as back on the road"
            )
        if self.vats_threshold_s > self.vats_window_s:
            raise ValueError(
                f"vats_threshold_s ({self.vats_threshold_s:g}) must not exceed vats_window_s "
                f"({self.vats_window_s:g})"
            )
        return self


class ZenohConfig(_Section):
    """Zenoh session and key expressions. Safe defaults: loopback only, no multicast scouting."""

    mode: Literal["peer", "client"] = "peer"
    """The daemon's session: `peer` opens at once, with or without a router; `client` needs its
    router to open (alerts raised before that are held by roadgaze, see docs/zenoh.md)."""
    connect: list[str] = Field(default_factory=list)
    listen: list[str] = Field(default_factory=list)
    rendezvous: str = "tcp/127.0.0.1:7447"
    """Where `run` and `listen` meet when `connect` and `listen` are both empty: the daemon
    connects here when something already listens (a router or another daemon) and listens here
    itself otherwise; `listen` connects here. '' for none."""
    multicast_scouting: bool = False
    config_file: Path | None = None
    """A Zenoh JSON5 config file; when set it is the base and the fields above override it."""
    vehicle_id: str = Field(default="car-0", pattern=VEHICLE_ID_PATTERN)
    prefix: str = "vehicle/{vehicle_id}/dms"
    speed_key: str = "vehicle/{vehicle_id}/speed"
    """Key expression of the speed input; '' for none. Without a (fresh) speed: taken as moving."""
    speed_timeout_s: float = Field(default=2.0, gt=0)
    """No valid speed for this long (monotonic time) means unknown, taken as moving. The old
    name `speed_stale_s` is still accepted."""
    alert_cache_size: int = Field(default=100, ge=1, le=10_000)
    """Alerts the daemon keeps for late and recovering subscribers (Zenoh advanced publisher)."""
    reconnect_initial_s: float = Field(default=0.25, gt=0)
    """First delay before retrying a `connect` endpoint or re-opening a client session."""
    reconnect_max_s: float = Field(default=1.0, gt=0)

    @model_validator(mode="before")
    @classmethod
    def _old_speed_timeout_name(cls, data: Any) -> Any:
        if isinstance(data, dict) and "speed_stale_s" in data:
            data = dict(data)
            if "speed_timeout_s" in data:
                raise ValueError("set speed_timeout_s only (speed_stale_s is its old name)")
            data["speed_timeout_s"] = data.pop("speed_stale_s")
        return data

    @field_validator("prefix", "speed_key")
    @classmethod
    def _key_template(cls, template: str, info: ValidationInfo) -> str:
        if template == "" and info.field_name == "speed_key":
            return template
        check_key_template(template)
        return template

    @model_validator(mode="after")
    def _backoff_order(self) -> Self:
        if self.reconnect_initial_s > self.reconnect_max_s:
            raise ValueError(
                f"reconnect_initial_s ({self.reconnect_initial_s:g}) must not exceed "
                f"reconnect_max_s ({self.reconnect_max_s:g})"
            )
        return self


def check_key_template(template: str) -> None:
    """Raise ValueError unless `template` makes a plain key expression for every vehicle id.

    Only the placeholder `{vehicle_id}` is allowed; chunks (between '/') must be non-empty and
    free of wildcards (`*`, `$`), `?`, `#` and a leading `@`; the longest key stays under
    `KEY_MAX_CHARS`.
    """
    try:
        key = template.format(vehicle_id="x" * 64)
    except (KeyError, IndexError, ValueError) as exc:
        raise ValueError(f"only the placeholder {{vehicle_id}} is allowed ({exc})") from None
    if len(key) > KEY_MAX_CHARS:
        raise ValueError(f"key expression longer than {KEY_MAX_CHARS} characters")
    chunks = key.split("/")
    bad = [chunk for chunk in chunks if not _KEY_CHUNK.fullmatch(chunk)]
    if bad:
        raise ValueError(
            f"each part between '/' must be non-empty, without wildcards, '?', '#' or '@'; "
            f"found {bad[0][:40]!r}"
        )


class LoggingConfig(_Section):
    level: Literal["DEBUG", "INFO", "WARNING", "ERROR"] = "INFO"
    json_format: bool = False


class Config(_Section):
    """The whole roadgaze configuration."""

    model: ModelConfig = ModelConfig()
    geometry: GeometryConfig = GeometryConfig()
    landmarks: LandmarksConfig = LandmarksConfig()
    capture: CaptureConfig = CaptureConfig()
    smoothing: SmoothingConfig = SmoothingConfig()
    monitor: MonitorConfig = MonitorConfig()
    zenoh: ZenohConfig = ZenohConfig()
    logging: LoggingConfig = LoggingConfig()


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
        if isinstance(found, dict):  # a check across fields: the message names them
            problems.append(f"{where}: {item['msg']}")
            continue
        text = repr(found)
        text = text if len(text) <= 80 else f"{text[:60]}... ({len(text)} characters)"
        problems.append(f"{where}: {item['msg']} (found {text})")
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
