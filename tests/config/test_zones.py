"""ADDW's area 1 cannot be configured away (`check_area1` and the bounds of `roof_pitch_deg` and
`distraction_yaw_deg`): the configurations that hid a 5 s look at the roof are refused in one
line naming the key, from a real command line, and the highest roof allowed still warns."""

from __future__ import annotations

from pathlib import Path

import pytest

from fakes import drive_monitor
from roadgaze.cli import main
from roadgaze.config import MonitorConfig
from roadgaze.monitor import Monitor

DEFAULT_ZONES_TOML = """
[[monitor.zones]]
name = "lap"
yaw_deg = [-25.0, 25.0]
pitch_deg = [-90.0, -18.0]

[[monitor.zones]]
name = "cluster"
yaw_deg = [-15.0, 15.0]
pitch_deg = [-18.0, -10.0]

[[monitor.zones]]
name = "centre_stack"
yaw_deg = [-55.0, -15.0]
pitch_deg = [-50.0, -5.0]

[[monitor.zones]]
name = "left_mirror"
yaw_deg = [20.0, 50.0]
pitch_deg = [-25.0, 10.0]

[[monitor.zones]]
name = "right_mirror"
yaw_deg = [-55.0, -30.0]
pitch_deg = [-25.0, 10.0]
"""

VISOR = """
[[monitor.zones]]
name = "visor"
yaw_deg = [-25.0, 25.0]
pitch_deg = [15.0, 90.0]
"""
VISOR_RELATED = 'driving_related_zones = ["left_mirror", "right_mirror", "visor"]\n'


@pytest.mark.parametrize(
    ("toml", "says"),
    [
        # The two configurations under which a 5 s look at the roof raised nothing or late.
        (
            "[monitor]\nroof_pitch_deg = 90\n" + VISOR_RELATED + DEFAULT_ZONES_TOML + VISOR,
            "monitor.roof_pitch_deg: Input should be less than or equal to 30 (found 90)",
        ),
        (
            "[monitor]\nroof_pitch_deg = 90\nroad_pitch_deg = [-10, 89]\n",
            "monitor.roof_pitch_deg: Input should be less than or equal to 30 (found 90)",
        ),
        # Within the bound: the visor and the road still may not reach the roof.
        (
            "[monitor]\nroof_pitch_deg = 30\n" + VISOR_RELATED + DEFAULT_ZONES_TOML + VISOR,
            "driving-related zone 'visor' (yaw [-25.0, 25.0], pitch [15.0, 90.0]) reaches into "
            "ADDW's distraction area 1",
        ),
        (
            "[monitor]\nroad_pitch_deg = [-10, 89]\n",
            "road_pitch_deg's top (89) must be below roof_pitch_deg (20)",
        ),
        (
            "[monitor]\nroof_pitch_deg = 30\nroad_pitch_deg = [-10, 30]\n",
            "road_pitch_deg's top (30) must be below roof_pitch_deg (30)",
        ),
        (
            "[monitor]\ndistraction_yaw_deg = 90\n",
            "monitor.distraction_yaw_deg: Input should be less than or equal to 55 (found 90)",
        ),
    ],
    ids=["roof-90-visor", "roof-90-road-89", "visor", "road-89", "road-at-roof", "yaw-90"],
)
def test_area_one_cannot_be_configured_away(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], toml: str, says: str
) -> None:
    config = tmp_path / "roadgaze.toml"
    config.write_text(toml)
    out = tmp_path / "frames.jsonl"
    code = main(["replay", str(tmp_path / "drive.mp4"), "--config", str(config), "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and says in err[0], err
    assert not out.exists()


def test_a_look_at_the_roof_warns_at_the_highest_roof_allowed() -> None:
    """At 30 deg (a look 60 deg up reads +30 on average), a 5 s look at a head pitch above it
    warns 3 s in, as at the default 20 deg."""
    from roadgaze.config.protocol import ROOF_PITCH_MAX_DEG

    with pytest.raises(ValueError, match="less than or equal to 30"):
        MonitorConfig(roof_pitch_deg=ROOF_PITCH_MAX_DEG + 0.5)
    for roof_deg in (20.0, ROOF_PITCH_MAX_DEG):
        config = MonitorConfig(roof_pitch_deg=roof_deg, road_pitch_deg=(-10.0, 15.0))
        look_up = roof_deg + 5.0

        def pose(t_s: float, pitch: float = look_up) -> tuple[float, float]:
            return (0.0, pitch if 3.0 <= t_s < 8.0 else 0.0)

        alerts = drive_monitor(Monitor(config), pose, 70.0, 10.0)
        warning = alerts[0]
        assert (warning.kind.value, warning.reason) == ("long_distraction", "head in roof")
        assert warning.t_s == pytest.approx(6.0, abs=1 / 15)
