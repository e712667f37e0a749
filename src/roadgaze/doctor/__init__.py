"""Doctor: what a user needs to know before filing a bug, one check per line (OK, WARN or FAIL)."""

from roadgaze.doctor.report import Check, Status, format_checks, run_checks, worst
from roadgaze.doctor.resources import (
    check_cameras,
    check_model,
    check_zenoh,
    endpoint_reachable,
)
from roadgaze.doctor.software import (
    OPENCV_DISTRIBUTIONS,
    check_egl,
    check_opencv,
    check_versions,
    opencv_fix,
)

__all__ = [
    "OPENCV_DISTRIBUTIONS",
    "Check",
    "Status",
    "check_cameras",
    "check_egl",
    "check_model",
    "check_opencv",
    "check_versions",
    "check_zenoh",
    "endpoint_reachable",
    "format_checks",
    "opencv_fix",
    "run_checks",
    "worst",
]
