"""Where the doctor's resource checks used to live; kept so `roadgaze.doctor.service` stays
importable. They are in `roadgaze.doctor.resources` ("service" names the service folder)."""

from roadgaze.doctor.resources import (
    CAMERA_TIMEOUT_S,
    ENDPOINT_TIMEOUT_S,
    camera_devices,
    check_cameras,
    check_model,
    check_zenoh,
    endpoint_reachable,
    explicit_model_check,
    landmarker_problem,
    open_camera,
    open_session_problem,
)

__all__ = [
    "CAMERA_TIMEOUT_S",
    "ENDPOINT_TIMEOUT_S",
    "camera_devices",
    "check_cameras",
    "check_model",
    "check_zenoh",
    "endpoint_reachable",
    "explicit_model_check",
    "landmarker_problem",
    "open_camera",
    "open_session_problem",
]
