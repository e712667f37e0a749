"""`roadgaze speed`: a constant or a CSV track put on the speed key at 10 Hz, on a schedule that
does not drift; bad tracks are one line; the daemon's parser takes every payload it puts."""

from __future__ import annotations

from pathlib import Path

import pytest

from roadgaze.cli import main
from roadgaze.errors import ConfigError
from roadgaze.transport.speed import parse_speed_kmh
from roadgaze.transport.speed_track import (
    SpeedTrack,
    publish_track,
    read_speed_track,
    speed_payload,
)
from zenoh_helpers import endpoint, free_port, router, wait_for


class FakeClock:
    """A clock that `wait` moves on, plus a late wake-up now and then."""

    def __init__(self) -> None:
        self.now_s = 100.0
        self.waits: list[float] = []

    def __call__(self) -> float:
        return self.now_s

    def wait(self, seconds: float) -> bool:
        self.waits.append(seconds)
        self.now_s += seconds + (0.03 if len(self.waits) % 3 == 0 else 0.0)  # woken late
        return False


def test_a_track_is_interpolated_and_published_to_its_end(tmp_path: Path) -> None:
    track_csv = tmp_path / "track.csv"
    track_csv.write_text("t_s,kmh\n0,0\n0.5,50\n0.5,50\n1.0,30\n")
    track = read_speed_track(track_csv)
    clock = FakeClock()
    puts: list[bytes] = []
    speeds = list(publish_track(track, puts.append, clock.wait, clock))
    assert speeds == pytest.approx([0, 10, 20, 30, 40, 50, 46, 42, 38, 34, 30])
    assert [parse_speed_kmh(p) for p in puts] == pytest.approx(speeds)
    # An absolute schedule: a late wake-up shortens the next wait, nothing drifts.
    assert clock.now_s - 100.0 == pytest.approx(1.1, abs=0.031)
    assert min(clock.waits) == pytest.approx(0.07)


def test_a_constant_runs_until_stopped_or_for_its_duration() -> None:
    clock = FakeClock()
    track = SpeedTrack.constant(57.0)
    assert len(list(publish_track(track, lambda _: None, clock.wait, clock, duration_s=2.0))) == 21
    stops = iter([False, False, True])
    published = list(publish_track(track, lambda _: None, lambda _: next(stops), clock))
    assert published == [57.0, 57.0, 57.0]


def test_a_looped_track_starts_again() -> None:
    clock = FakeClock()
    track = SpeedTrack((0.0, 0.2), (10.0, 30.0))
    speeds = list(
        publish_track(track, lambda _: None, clock.wait, clock, loop=True, duration_s=0.5)
    )
    assert speeds == pytest.approx([10, 20, 10, 20, 10, 20])


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("t,speed\n0,1\n", "needs the columns t_s,kmh"),
        ("t_s,kmh\n0,fast\n", "track.csv:2: t_s and kmh must be numbers"),
        ("t_s,kmh\n0,401\n", "track.csv:2: speed must be within 0-400"),
        ("t_s,kmh\n1,1\n0,1\n", "track.csv:3: t_s must be >= 0 and non-decreasing"),
        ("t_s,kmh\n", "no rows"),
    ],
)
def test_bad_tracks_are_refused_with_file_and_line(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "track.csv"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message):
        read_speed_track(path)


def test_the_payload_is_what_the_daemon_reads() -> None:
    assert speed_payload(57.25) == b'{"kmh": 57.25}'
    assert parse_speed_kmh(speed_payload(0.0)) == 0.0
    with pytest.raises(ConfigError, match="within 0-400"):
        SpeedTrack.constant(-1.0)


def test_the_command_puts_the_speed_on_the_key(capsys: pytest.CaptureFixture[str]) -> None:
    port = free_port()
    received: list[bytes] = []
    with router(port) as session:
        subscriber = session.declare_subscriber(
            "vehicle/car-7/speed", lambda sample: received.append(sample.payload.to_bytes())
        )
        argv = ["speed", "--kmh", "57", "--duration", "0.6", "--vehicle-id", "car-7"]
        argv += ["--zenoh-connect", endpoint(port)]
        assert main(argv) == 0
        assert wait_for(lambda: len(received) >= 5, timeout_s=5.0)
        subscriber.undeclare()
    assert all(parse_speed_kmh(payload) == 57.0 for payload in received)
    assert 5 <= len(received) <= 7  # 0.6 s at 10 Hz: 7 puts, the first may precede the link
    err = capsys.readouterr().err
    assert "7 speeds published, the last 57 km/h" in err
    assert main(["speed", "--kmh", "500"]) == 2
    assert "speed must be within 0-400 km/h" in capsys.readouterr().err
