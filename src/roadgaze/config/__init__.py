"""Configuration: pydantic sections from defaults, a TOML file, the environment and `--set`."""

from roadgaze.config.eyes import EyeMonitorSettings, EyesConfig
from roadgaze.config.hands import HandsConfig
from roadgaze.config.record import RecordConfig
from roadgaze.config.section import Section
from roadgaze.config.settings import (
    ENV_PREFIX,
    YAW_MODEL_NAMES,
    CaptureConfig,
    Config,
    GeometryConfig,
    LandmarksConfig,
    LoggingConfig,
    ModelConfig,
    MonitorConfig,
    PoseConfig,
    SmoothingConfig,
    load_config,
    parse_overrides,
)
from roadgaze.config.zenoh import (
    KEY_MAX_CHARS,
    VEHICLE_ID_PATTERN,
    ZenohConfig,
    check_key_template,
)
from roadgaze.config.zones import ZoneConfig

__all__ = [
    "ENV_PREFIX",
    "KEY_MAX_CHARS",
    "VEHICLE_ID_PATTERN",
    "YAW_MODEL_NAMES",
    "CaptureConfig",
    "Config",
    "EyeMonitorSettings",
    "EyesConfig",
    "GeometryConfig",
    "HandsConfig",
    "LandmarksConfig",
    "LoggingConfig",
    "ModelConfig",
    "MonitorConfig",
    "PoseConfig",
    "RecordConfig",
    "Section",
    "SmoothingConfig",
    "ZenohConfig",
    "ZoneConfig",
    "check_key_template",
    "load_config",
    "parse_overrides",
]
