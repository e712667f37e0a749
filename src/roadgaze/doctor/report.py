"""The doctor's checks, their verdicts and the one-screen report."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from enum import StrEnum
from typing import Any

from roadgaze.config import Config


class Status(StrEnum):
    OK = "OK"
    WARN = "WARN"
    """Works, but something a user should know (or fix before it bites)."""
    FAIL = "FAIL"
    """Broken: the service cannot do its job this way."""


@dataclass(frozen=True, slots=True)
class Check:
    """One line of the report."""

    area: str
    """What was checked: `python`, `opencv`, `model`, `zenoh`, `camera` ..."""
    status: Status
    detail: str
    fix: str | None = None
    """What to do about a WARN or FAIL."""

    def to_json_dict(self) -> dict[str, Any]:
        return {
            key: str(value) if key == "status" else value for key, value in asdict(self).items()
        }


def worst(checks: Sequence[Check]) -> Status:
    """FAIL if any check failed, else WARN if any warned, else OK."""
    statuses = {check.status for check in checks}
    for status in (Status.FAIL, Status.WARN):
        if status in statuses:
            return status
    return Status.OK


def run_checks(config: Config) -> list[Check]:
    """Every check, in report order. A check that crashes is reported as a FAIL line."""
    from roadgaze.doctor.hands import check_hands
    from roadgaze.doctor.resources import check_cameras, check_model, check_zenoh
    from roadgaze.doctor.software import check_egl, check_opencv, check_versions

    groups: list[tuple[str, Callable[[], list[Check]]]] = [
        ("versions", check_versions),
        ("opencv", check_opencv),
        ("egl", check_egl),
        ("model", lambda: check_model(config)),
        ("hands", lambda: check_hands(config)),
        ("zenoh", lambda: check_zenoh(config)),
        ("camera", check_cameras),
    ]
    checks: list[Check] = []
    for area, group in groups:
        try:
            checks.extend(group())
        except Exception as exc:  # a doctor reports, it does not crash
            checks.append(Check(area, Status.FAIL, f"the check itself failed: {exc!r}"))
    return checks


def format_checks(checks: Sequence[Check]) -> str:
    """One line per check (`STATUS  area  detail`), fixes indented below, a summary line."""
    width = max((len(check.area) for check in checks), default=0)
    lines = []
    for check in checks:
        lines.append(f"{check.status.value:<4}  {check.area:<{width}}  {check.detail}")
        if check.fix:
            lines.append(f"{'':<4}  {'':<{width}}  fix: {check.fix}")
    counts = {status: sum(c.status is status for c in checks) for status in Status}
    lines.append(
        f"{worst(checks).value}: {counts[Status.OK]} ok, {counts[Status.WARN]} warnings, "
        f"{counts[Status.FAIL]} failures"
    )
    return "\n".join(lines)
