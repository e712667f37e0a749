"""`roadgaze speed`'s publisher: a constant or a track put on the speed key at 10 Hz and at each
instant the track's held speed changes, on a schedule that does not drift; the daemon's parser
takes every payload it puts; the command logs as itself and ends with its totals."""

from __future__ import annotations

import signal
import subprocess
import sys
from pathlib import Path

import pytest

from repo_paths import child_env
from roadgaze.cli import main
from roadgaze.speed import SpeedTrack, read_speed_track
from roadgaze.transport.payloads import PayloadError
from roadgaze.transport.speed import (
    SpeedInput,
    parse_speed_kmh,
    publish_track,
    speed_payload,
)
from zenoh_helpers import LineReader, endpoint, free_port, router, stop_process, wait_for


class FakeClock:
    """A clock that `wait` moves on, plus a late wake-up now and then."""

    def __init__(self, late_s: float = 0.03) -> None:
        self.now_s = 100.0
        self.late_s = late_s
        self.waits: list[float] = []

    def __call__(self) -> float:
        return self.now_s

    def wait(self, seconds: float) -> bool:
        self.waits.append(seconds)
        self.now_s += seconds + (self.late_s if len(self.waits) % 3 == 0 else 0.0)  # late
        return False


def test_a_track_is_held_put_at_each_change_and_to_the_end_of_its_last_hold(
    tmp_path: Path,
) -> None:
    track_csv = tmp_path / "track.csv"
    track_csv.write_text("t_s,kmh\n0,0\n0.25,50\n0.5,\n0.6,30\n")
    track = read_speed_track(track_csv, hold_s=0.3)
    clock = FakeClock(late_s=0.0)
    puts: list[tuple[float, bytes]] = []
    speeds = list(
        publish_track(track, lambda p: puts.append((clock.now_s - 100.0, p)), clock.wait, clock)
    )
    times = [round(t, 6) for t, _ in puts]
    assert times == [0.0, 0.1, 0.2, 0.25, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9]
    assert speeds == [0, 0, 0, 50, 50, 50, None, 30, 30, 30, None]  # never interpolated
    assert [track.kmh_at(t) for t in times] == speeds
    parsed = [
        None if s is None else parse_speed_kmh(p) for (_, p), s in zip(puts, speeds, strict=True)
    ]
    assert parsed == speeds
    assert puts[-1][1] == b'{"kmh": null}'  # the last sample's hold ended: unknown


def test_the_schedule_does_not_drift_when_woken_late() -> None:
    clock = FakeClock()
    track = SpeedTrack.constant(57.0)
    assert len(list(publish_track(track, lambda _: None, clock.wait, clock, duration_s=2.0))) == 21
    assert clock.now_s - 100.0 == pytest.approx(2.0, abs=0.031)
    assert min(clock.waits) == pytest.approx(0.07)
    stops = iter([False, False, True])
    published = list(publish_track(track, lambda _: None, lambda _: next(stops), clock))
    assert published == [57.0, 57.0, 57.0]


def test_a_looped_track_starts_again() -> None:
    clock = FakeClock(late_s=0.0)
    track = SpeedTrack((0.0, 0.2), (10.0, 30.0))
    speeds = list(
        publish_track(track, lambda _: None, clock.wait, clock, loop=True, duration_s=0.5)
    )
    assert speeds == [10, 10, 10, 10, 10, 10]  # 0.2 is the wrap: the track starts again there
    track = SpeedTrack((0.0, 0.1, 0.3), (10.0, 30.0, 0.0))
    speeds = list(
        publish_track(track, lambda _: None, clock.wait, clock, loop=True, duration_s=0.5)
    )
    assert speeds == [10, 30, 30, 10, 30, 30]


def test_the_payload_is_what_the_daemon_reads() -> None:
    assert speed_payload(57.25) == b'{"kmh": 57.25}'
    assert parse_speed_kmh(speed_payload(0.0)) == 0.0
    assert parse_speed_kmh(speed_payload(1 / 3)) == 1 / 3  # not rounded: the track's value
    with pytest.raises(PayloadError, match="kmh null: the sender does not know the speed"):
        parse_speed_kmh(speed_payload(None))
    speed = SpeedInput(timeout_s=2.0, clock=lambda: 0.0)
    speed.on_payload(speed_payload(40.0))
    assert speed.kmh() == 40.0
    speed.on_payload(speed_payload(None))
    assert speed.kmh() is None and speed.current() == (None, "invalid")  # unknown at once


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
    assert "roadgaze.speed: roadgaze speed: 7 speeds published, the last 57 km/h (0.6 s)" in err
    assert main(["speed", "--kmh", "500"]) == 2
    assert "--kmh 500 is not a speed within 0-400 km/h" in capsys.readouterr().err


def test_stopped_it_logs_as_itself_and_says_what_it_published(tmp_path: Path) -> None:
    """SIGINT while it waits for a router: its own logger (not the daemon's) and a totals
    line, exit 0."""
    nowhere = f"tcp/127.0.0.1:{free_port()}"
    process = subprocess.Popen(
        [sys.executable, "-m", "roadgaze", "speed", "--kmh", "50", "--zenoh-connect", nowhere],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=child_env(),
    )
    try:
        reader = LineReader(process, process.stderr)
        reader.until("roadgaze speed: client session", 60.0)
        process.send_signal(signal.SIGINT)
        assert process.wait(timeout=30) == 0
        lines = reader.until("roadgaze speed: no speed published", 10.0)
    finally:
        stop_process(process)
    text = "\n".join(lines)
    assert "roadgaze.speed: SIGINT received: stopping" in text
    assert "roadgaze.daemon" not in text
