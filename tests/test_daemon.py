"""`roadgaze run` and `roadgaze replay --publish` end to end, over real Zenoh on loopback.

End-to-end tests use real MediaPipe on clips of the synthetic face (roadgaze.synth, so a fresh
clone runs them) and, where the evaluation data is present, on clips built from Pointing'04
stills (Person01: frontal, 45 deg to the left, looking down 60 deg); a Python router session
stands in for zenohd on a free loopback port, and the daemon runs in a subprocess that is always
terminated.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import jsonschema
import pytest
import zenoh

from fakes import FakeCamera
from repo_paths import POINTING04, child_env
from roadgaze.config import Config
from roadgaze.logs import setup_logging
from roadgaze.transport import json_schemas
from zenoh_helpers import LineReader, endpoint, free_port, router, stop_process, wait_for

CLIP_FPS = 15
STILLS = POINTING04 / "images" / "Person01"
FRONTAL = STILLS / "person01146+0+0.jpg"
SIDE_45 = STILLS / "person01143+0-45.jpg"  # pan -45: yaw +45, turned to the person's left
DOWN_60 = STILLS / "person01107-60+0.jpg"  # tilt -60: looking down into the lap
STILL_OF_POSE = {"road": FRONTAL, "left45": SIDE_45, "lap": DOWN_60}
SYNTHETIC_POSE = {"road": "0/0", "left45": "45/0", "lap": "0/-35"}
"""Each pose as a synthetic YAW/PITCH and as a Pointing'04 still."""
SCHEMAS = json_schemas()
ENV = child_env(GLOG_minloglevel="2")


@pytest.fixture(autouse=True)
def fresh_log_handler() -> None:
    """Log to this test's stderr (an earlier in-process CLI test may have left a closed one)."""
    setup_logging()


def synthetic_clip_file(path: Path, renderer: Any, segments: list[tuple[str, float]]) -> Path:
    """An MJPG clip of the synthetic face holding each (pose, seconds) with abrupt cuts."""
    from roadgaze.synth import parse_timeline, render_clip

    spec = ",".join(f"{SYNTHETIC_POSE[pose]}:{seconds:g}" for pose, seconds in segments)
    render_clip(parse_timeline(spec, transition_s=0.0), path, fps=CLIP_FPS, renderer=renderer)
    return path


def stills_clip_file(path: Path, segments: list[tuple[str, float]]) -> Path:
    """An MJPG clip of Pointing'04 Person01 stills (one per pose) with abrupt cuts."""
    import cv2

    if not FRONTAL.is_file():
        pytest.skip(f"Pointing'04 stills not found under {STILLS} (evaluation data)")
    images = {pose: cv2.imread(str(still)) for pose, still in STILL_OF_POSE.items()}
    height, width = images["road"].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), CLIP_FPS, (width, height))
    try:
        for pose, seconds in segments:
            for _ in range(round(seconds * CLIP_FPS)):
                writer.write(images[pose])
    finally:
        writer.release()
    return path


GLANCE = [("road", 4.0), ("lap", 4.0), ("road", 4.0)]
"""Road 4 s, a look down into the lap for 4 s, road 4 s. (Before zones: a 45 deg glance to the
left, which the default zones now call the left mirror: no long distraction.)"""
FIVE_GLANCES = [("road", 2.0)] + [("left45", 2.5), ("road", 1.0)] * 5 + [("road", 1.0)]
"""Five 2.5 s glances 45 deg to the left (the left mirror: counted for VATS)."""


@pytest.fixture(scope="module")
def glance_clip(tmp_path_factory: pytest.TempPathFactory, synthetic_renderer: Any) -> Path:
    """The glance rendered from the synthetic face (roadgaze.synth): needs no evaluation data."""
    folder = tmp_path_factory.mktemp("clips")
    return synthetic_clip_file(folder / "glance.avi", synthetic_renderer, GLANCE)


def _clip(
    request: pytest.FixtureRequest,
    tmp_path_factory: pytest.TempPathFactory,
    segments: list[tuple[str, float]],
) -> Path:
    path = tmp_path_factory.mktemp("clips") / "clip.avi"
    if request.param == "pointing04":
        return stills_clip_file(path, segments)
    return synthetic_clip_file(path, request.getfixturevalue("synthetic_renderer"), segments)


@pytest.fixture(scope="module", params=["synthetic", "pointing04"])
def glance_clips(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The glance from the synthetic face and from real Pointing'04 stills (skipped without)."""
    return _clip(request, tmp_path_factory, GLANCE)


@pytest.fixture(scope="module", params=["synthetic", "pointing04"])
def vats_clip(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Five 2.5 s glances with 1 s on road between, synthetic and from Pointing'04 stills."""
    return _clip(request, tmp_path_factory, FIVE_GLANCES)


class Hub:
    """A router session recording everything published under one vehicle's prefix."""

    def __init__(self, session: zenoh.Session, vehicle_id: str) -> None:
        self.session = session
        self.prefix = f"vehicle/{vehicle_id}/dms"
        self.messages: list[tuple[str, dict[str, Any]]] = []
        self.alive: list[bool] = []
        self._entities = [
            session.declare_subscriber(f"{self.prefix}/**", self._on_sample),
            session.liveliness().declare_subscriber(
                f"{self.prefix}/alive",
                lambda s: self.alive.append(s.kind == zenoh.SampleKind.PUT),
                history=True,
            ),
        ]

    def _on_sample(self, sample: zenoh.Sample) -> None:
        kind = str(sample.key_expr).rsplit("/", 1)[-1]
        self.messages.append((kind, json.loads(sample.payload.to_bytes())))

    def of(self, kind: str) -> list[dict[str, Any]]:
        return [payload for k, payload in list(self.messages) if k == kind]

    def query_state(self) -> dict[str, Any] | None:
        for reply in self.session.get(f"{self.prefix}/state", timeout=5.0):
            if reply.ok is not None:
                state: dict[str, Any] = json.loads(reply.ok.payload.to_bytes())
                return state
        return None

    def close(self) -> None:
        for entity in self._entities:
            entity.undeclare()


@pytest.fixture
def hub() -> Iterator[tuple[Hub, int]]:
    port = free_port()
    with router(port) as session:
        recorder = Hub(session, "e2e")
        try:
            yield recorder, port
        finally:
            recorder.close()


def roadgaze(*args: str, **kwargs: Any) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "roadgaze", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=ENV,
        **kwargs,
    )


def replay_publish(clip: Path, port: int, out: Path) -> subprocess.CompletedProcess[str]:
    process = roadgaze(
        "replay",
        str(clip),
        "--publish",
        "--vehicle-id",
        "e2e",
        "--zenoh-connect",
        endpoint(port),
        "--no-progress",
        "--out",
        str(out),
    )
    try:
        stdout, stderr = process.communicate(timeout=180)
    finally:
        stop_process(process)
    return subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)


@pytest.mark.slow
def test_replay_publish_one_long_distraction_three_seconds_into_the_glance(
    glance_clips: Path, hub: tuple[Hub, int], tmp_path: Path
) -> None:
    recorder, port = hub
    result = replay_publish(glance_clips, port, tmp_path / "frames.jsonl")
    assert result.returncode == 0, result.stderr[-2000:]
    assert wait_for(lambda: len(recorder.of("alert")) >= 2, timeout_s=5.0)
    alerts = recorder.of("alert")
    for alert in alerts:
        jsonschema.validate(alert, SCHEMAS["alert"])
    assert [(a["kind"], a["level"]) for a in alerts] == [
        ("long_distraction", "warning"),
        ("cleared", "info"),
    ]
    print(f"long_distraction at t={alerts[0]['t_s']:.3f}s, cleared at t={alerts[1]['t_s']:.3f}s")
    assert alerts[0]["t_s"] == pytest.approx(4.0 + 3.0, abs=0.5)
    assert 8.0 <= alerts[1]["t_s"] <= 8.5
    assert alerts[0]["vehicle_id"] == "e2e"
    yaws = recorder.of("yaw")
    assert len(yaws) == 12 * CLIP_FPS
    assert [y["seq"] for y in yaws] == list(range(len(yaws)))
    jsonschema.validate(yaws[100], SCHEMAS["yaw"])
    assert yaws[100]["on_road"] is False and yaws[30]["on_road"] is True
    assert (yaws[100]["zone"], yaws[100]["eyes_on_road"]) == ("lap", False)
    assert yaws[30]["zone"] == "road" and yaws[100]["schema"] == "roadgaze.yaw/3"
    assert yaws[100]["pitch_deg"] - yaws[100]["neutral_pitch_deg"] < -25.0
    assert yaws[100]["t_s"] == pytest.approx(100 / CLIP_FPS, abs=1e-3)  # the video's timeline
    records = [json.loads(line) for line in (tmp_path / "frames.jsonl").read_text().splitlines()]
    assert [r["on_road"] for r in records[95:106]] == [False] * 11
    assert sum(r["alerts"] == ["long_distraction:warning"] for r in records) == 1
    assert recorder.alive[:1] == [True] and recorder.alive[-1] is False
    assert recorder.of("state")[-1]["status"] == "stopped"


@pytest.mark.slow
def test_replay_publish_five_short_glances_one_vats_no_long_distraction(
    vats_clip: Path, hub: tuple[Hub, int], tmp_path: Path
) -> None:
    recorder, port = hub
    result = replay_publish(vats_clip, port, tmp_path / "frames.jsonl")
    assert result.returncode == 0, result.stderr[-2000:]
    assert wait_for(lambda: any(a["kind"] == "vats" for a in recorder.of("alert")), timeout_s=5.0)
    kinds = [a["kind"] for a in recorder.of("alert")]
    assert kinds.count("vats") == 1
    assert "long_distraction" not in kinds  # 2.5 s glances; the left mirror does not run it
    vats = next(a for a in recorder.of("alert") if a["kind"] == "vats")
    print(f"vats at t={vats['t_s']:.3f}s, window {vats['window_off_road_s']:.2f}s")
    # Four glances of 2.5 s (2.0-4.5, 5.5-8.0, 9.0-11.5, 12.5-15.0 s) make 10 s at t = 15.0 s.
    assert vats["t_s"] == pytest.approx(15.0, abs=0.5)
    assert vats["window_off_road_s"] >= 10.0


def run_daemon_process(source: str, port: int, *extra: str) -> subprocess.Popen[str]:
    return roadgaze(
        "run",
        "--source",
        source,
        "--vehicle-id",
        "e2e",
        "--zenoh-connect",
        endpoint(port),
        "--log-json",
        *extra,
    )


@pytest.mark.slow
def test_daemon_sigterm_publishes_final_state_and_its_token_goes_away(
    glance_clip: Path, hub: tuple[Hub, int]
) -> None:
    recorder, port = hub
    daemon = run_daemon_process(str(glance_clip), port)
    try:
        assert wait_for(lambda: len(recorder.of("yaw")) >= 15, timeout_s=60.0)
        assert recorder.alive == [True]
        state = recorder.query_state()
        assert state is not None
        jsonschema.validate(state, SCHEMAS["state"])
        assert state["status"] == "running" and state["frames"] >= 15
        assert state["transport"]["connected"] is True
        daemon.send_signal(signal.SIGTERM)
        code = daemon.wait(timeout=20)
        stderr = daemon.stderr.read() if daemon.stderr else ""
    finally:
        stop_process(daemon)
    assert code == 0, stderr[-2000:]
    assert wait_for(lambda: recorder.alive == [True, False], timeout_s=5.0)
    # The token's DELETE and the final state travel apart: either may come first.
    stopped = wait_for(lambda: any(s["status"] == "stopped" for s in recorder.of("state")), 10.0)
    assert stopped, ([s["status"] for s in recorder.of("state")], stderr[-3000:])
    final = recorder.of("state")[-1]
    assert final["status"] == "stopped"
    # The final state counts every frame sent; yaw goes with congestion control DROP, so a loaded
    # machine may receive fewer than were sent, never more.
    assert final["transport"]["yaw_sent"] == final["frames"] >= len(recorder.of("yaw")) >= 15
    logs = [json.loads(line) for line in stderr.splitlines() if line.startswith("{")]
    assert any("SIGTERM received" in entry["message"] for entry in logs)


@pytest.mark.slow
def test_daemon_keeps_monitoring_while_the_peer_is_unreachable(glance_clip: Path) -> None:
    port = free_port()
    daemon = run_daemon_process(str(glance_clip), port)
    try:
        LineReader(daemon, daemon.stderr).until("roadgaze run: source", 60.0)
        time.sleep(3.0)  # monitoring while nothing listens on the port
        assert daemon.poll() is None
        with router(port) as session:
            recorder = Hub(session, "e2e")
            try:
                assert wait_for(lambda: len(recorder.of("yaw")) >= 5, timeout_s=30.0)
                first_seq = recorder.of("yaw")[0]["seq"]
                state = recorder.query_state()
            finally:
                recorder.close()
        daemon.send_signal(signal.SIGTERM)
        assert daemon.wait(timeout=20) == 0
    finally:
        stop_process(daemon)
    print(f"first yaw received after the router came up: seq {first_seq}")
    assert first_seq >= 15  # frames were processed (and counted) while nobody was reachable
    assert state is not None and state["frames"] > first_seq


@pytest.mark.slow
def test_daemon_reports_an_unavailable_camera_and_stops_cleanly(hub: tuple[Hub, int]) -> None:
    recorder, port = hub
    daemon = run_daemon_process("/dev/video97", port, "--set", "capture.reconnect_max_s=0.5")
    try:
        assert wait_for(lambda: recorder.alive == [True], timeout_s=30.0)
        assert wait_for(
            lambda: ((recorder.query_state() or {}).get("camera_reopens") or 0) >= 2,
            timeout_s=15.0,
        )
        state = recorder.query_state()
        health = roadgaze(
            "listen", "--query-state", "--vehicle-id", "e2e", "--zenoh-connect", endpoint(port)
        )
        try:
            health_out, _ = health.communicate(timeout=60)
        finally:
            stop_process(health)
        assert daemon.poll() is None
        daemon.send_signal(signal.SIGTERM)
        assert daemon.wait(timeout=20) == 0
    finally:
        stop_process(daemon)
    assert state is not None
    assert state["status"] == "degraded" and state["source_status"] == "unavailable"
    assert "camera unavailable" in state["problems"][0]
    assert state["frames"] == 0
    assert health.returncode == 3  # answered, but degraded: the container health check fails
    assert "status=degraded" in health_out
    assert wait_for(lambda: recorder.alive == [True, False], timeout_s=5.0)


def test_run_with_a_missing_file_is_one_line_error(tmp_path: Path) -> None:
    process = roadgaze(
        "run", "--source", str(tmp_path / "nope.avi"), "--zenoh-listen", "tcp/127.0.0.1:0"
    )
    try:
        _, stderr = process.communicate(timeout=60)
    finally:
        stop_process(process)
    assert process.returncode == 2
    assert stderr.strip().splitlines()[-1].startswith("roadgaze run: error: no video file")


@pytest.mark.slow
def test_daemon_reports_a_lost_camera_and_carries_on_when_it_is_back(
    hub: tuple[Hub, int], monkeypatch: pytest.MonkeyPatch, synthetic_renderer: Any
) -> None:
    import threading

    import roadgaze.capture as capture
    from roadgaze.daemon import run_daemon
    from roadgaze.service.signals import StopFlag

    recorder, port = hub
    image = synthetic_renderer.render(0.0)
    # First plug: 60 frames then the camera vanishes; two failed re-opens; then it is back.
    period_s = 1 / 30
    plugs = iter(
        [
            FakeCamera(60, image=image, period_s=period_s),
            FakeCamera(0, image=image, opened=False),
            FakeCamera(0, image=image, opened=False),
        ]
    )

    def factory(device: int | str) -> FakeCamera:
        return next(plugs, None) or FakeCamera(None, image=image, period_s=period_s)

    def open_fake(
        spec: str, config: Config | None = None, *, wait_for_camera: bool = False
    ) -> capture.FrameSource:
        assert config is not None and wait_for_camera
        return capture.CameraSource(
            spec, config.capture, capture_factory=factory, wait_for_device=True
        )

    monkeypatch.setattr(capture, "open_source", open_fake)
    config = Config.model_validate(
        {
            "zenoh": {"vehicle_id": "e2e", "connect": [endpoint(port)]},
            "capture": {"reconnect_initial_s": 0.3, "reconnect_max_s": 1.0},
        }
    )
    stop = StopFlag()
    result: list[int] = []
    thread = threading.Thread(
        target=lambda: result.append(run_daemon(config, "/dev/video42", stop, True, False)),
        daemon=True,
    )
    thread.start()
    states: list[dict[str, Any]] = []
    try:

        def poll(predicate: Any) -> bool:
            state = recorder.query_state()
            if state is not None:
                states.append(state)
            return state is not None and bool(predicate(state))

        assert wait_for(lambda: poll(lambda s: s["source_status"] == "reconnecting"), 60.0, 0.1)
        assert wait_for(lambda: poll(lambda s: s["camera_reopens"] >= 1), 30.0, 0.1)
        reopened_at = states[-1]["frames"]
        assert wait_for(lambda: poll(lambda s: s["frames"] >= reopened_at + 10), 30.0, 0.1)
    finally:
        stop.set("test")
        thread.join(timeout=30)
    assert result == [0]
    lost = next(s for s in states if s["source_status"] == "reconnecting")
    assert lost["status"] == "degraded" and "lost" in lost["problems"][0]
    assert 0 < lost["frames"] <= 60  # newest-frame-only: some of the 60 may be dropped
    back = states[-1]
    print(
        f"lost: {lost['status']} {lost['problems']} after {lost['frames']} frames; back: "
        f"{back['status']}, camera_reopens {back['camera_reopens']}, frames {back['frames']}"
    )
    assert back["status"] == "running" and back["problems"] == []
    # the final state is put at shutdown; it may reach the recorder just after run_daemon returns
    assert wait_for(lambda: any(s["status"] == "stopped" for s in recorder.of("state")), 5.0)


# --- Faults on a daemon with a scripted camera and detector (tests/fake_daemon.py) -------------

FAKE_DAEMON = Path(__file__).resolve().parent / "fake_daemon.py"


def fake_daemon(vehicle_id: str, port: int, *extra: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, str(FAKE_DAEMON), *extra, "--vehicle-id", vehicle_id,
         "--zenoh-connect", endpoint(port)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV,
    )  # fmt: skip


SIGNALS = [signal.SIGINT, signal.SIGTERM, signal.SIGHUP]
BLOCK = zenoh.CongestionControl.BLOCK
"""For test puts that must not be dropped by a busy machine (the default is DROP)."""


@pytest.mark.parametrize("times", [1, 2], ids=["once", "twice"])
@pytest.mark.parametrize("number", SIGNALS, ids=lambda n: signal.Signals(n).name)
def test_signal_matrix(
    number: int, times: int, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """`roadgaze run` (in this process, scripted camera and detector): SIGINT, SIGTERM and
    SIGHUP once finish the frame, put the final state and return 0; twice (during one long
    frame) call `exit_now(1)` without waiting (from the signal thread; here recorded instead of
    ending the test's process). The subprocess form: the hostile-speed test below."""
    import os
    import threading

    import roadgaze.capture
    import roadgaze.pipeline
    import roadgaze.service.signals
    from fake_daemon import EndlessSource, GlancingDetector
    from roadgaze.cli import main

    exits: list[int] = []

    def exit_now(code: int) -> None:  # the real one ends this test process at once
        exits.append(code)

    monkeypatch.setattr(roadgaze.service.signals, "exit_now", exit_now)
    frame_s = 0.05 if times == 1 else 1.5
    monkeypatch.setattr(roadgaze.pipeline, "create_detector", lambda c: GlancingDetector(frame_s))
    monkeypatch.setattr(roadgaze.capture, "open_source", lambda *a, **k: EndlessSource())
    port = free_port()
    name = signal.Signals(number).name
    with router(port) as session:
        hub = Hub(session, "sig")

        def send() -> None:
            assert wait_for(lambda: len(hub.of("yaw")) >= 1, timeout_s=30.0)
            os.kill(os.getpid(), number)
            if times == 2:
                time.sleep(0.3)  # inside the same 1.5 s frame
                os.kill(os.getpid(), number)

        sender = threading.Thread(target=send, daemon=True)
        sender.start()
        started = time.monotonic()
        args = ["run", "--source", "fake", "--vehicle-id", "sig", "--zenoh-connect",
                endpoint(port)]  # fmt: skip
        code = main(args)
        sender.join(timeout=30)
        if times == 2:
            assert wait_for(lambda: exits == [1], timeout_s=10.0)
        elapsed_s = time.monotonic() - started
        if times == 1:  # the final state on its way to the hub (asserted below)
            wait_for(lambda: [s["status"] for s in hub.of("state")][-1:] == ["stopped"], 10.0)
        hub.close()
    stderr = capsys.readouterr().err
    assert f"{name} received" in stderr
    if times == 1:
        assert code == 0
        assert f"stopping ({name})" in stderr
        assert hub.of("state")[-1]["status"] == "stopped"
    else:
        assert exits == [1]
        assert f"second {name}: exiting without waiting" in stderr
        assert elapsed_s < 20.0


def test_daemon_survives_hostile_speed_payloads_and_counts_them() -> None:
    """Deep JSON, 10 MB, non-UTF-8, NaN and 1e308 km/h on the speed key: no traceback, the
    oversize ones dropped unread and counted, the speed unknown (moving): alerts still fire."""
    port = free_port()
    with router(port) as session:
        hub = Hub(session, "hostile")
        daemon = fake_daemon("hostile", port)
        try:
            assert wait_for(lambda: hub.alive == [True], timeout_s=60.0)
            hostile = [b"[" * 100_000, b"x" * 10_000_000, b"\xff\xfe", b"NaN", b"1e308",
                       b'{"kmh": ' * 1000]  # fmt: skip
            for _ in range(3):
                for payload in hostile:
                    session.put("vehicle/hostile/speed", payload, congestion_control=BLOCK)
                    time.sleep(0.05)
            assert wait_for(lambda: len(hub.of("alert")) >= 1, timeout_s=15.0)
            state = hub.query_state()
            daemon.send_signal(signal.SIGTERM)
            code = daemon.wait(timeout=30)
            stderr = daemon.stderr.read() if daemon.stderr else ""
        finally:
            stop_process(daemon)
            hub.close()
    assert code == 0 and "Traceback" not in stderr, stderr[-2000:]
    assert state is not None
    assert state["transport"]["speed_oversize"] >= 1
    assert state["monitor"]["speed_source"] in ("invalid", "stale")
    assert state["monitor"]["moving"] is True
    assert hub.of("alert")[0]["kind"] == "long_distraction"
    assert stderr.count("ignored speed message") <= 3  # rate-limited


@pytest.mark.parametrize("vehicle_id", ["*", "", "car/1", "x" * 100_000])
def test_run_refuses_a_vehicle_id_that_is_not_one_vehicle(
    vehicle_id: str, capsys: pytest.CaptureFixture[str]
) -> None:
    from roadgaze.cli import main

    assert main(["run", "--source", "/dev/video97", "--vehicle-id", vehicle_id]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "--vehicle-id" in lines[0] and len(lines[0]) < 400, lines[:3]


@pytest.mark.parametrize("with_router", [False, True], ids=["alone", "router-on-the-port"])
def test_run_and_listen_without_endpoint_flags_find_each_other(with_router: bool) -> None:
    """The documented default: both meet at the rendezvous endpoint (7447 in real use; a free
    port here, set through the environment like a user's setting). `run` logs where it listens or
    connects and says "connected" only once a consumer (or the router) really is."""
    from contextlib import nullcontext

    port = free_port()
    env = ENV | {"ROADGAZE__ZENOH__RENDEZVOUS": endpoint(port)}
    with router(port) if with_router else nullcontext():
        daemon = subprocess.Popen(
            [sys.executable, str(FAKE_DAEMON), "--vehicle-id", "meet"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
        )  # fmt: skip
        listener: subprocess.Popen[str] | None = None
        try:
            daemon_log = LineReader(daemon, daemon.stderr)
            lines = daemon_log.until("roadgaze run: source", 60.0)
            if not with_router:
                time.sleep(1.0)  # nobody there: no "connected" may come meanwhile
            elif not any("zenoh connected" in line for line in lines):
                lines += daemon_log.until("zenoh connected", 30.0)  # the router is there
            while (line := daemon_log.next(0.1)) is not None:
                lines.append(line)
            connected_alone = any("zenoh connected" in line for line in lines)
            listener = subprocess.Popen(
                [sys.executable, "-m", "roadgaze", "listen", "--no-yaw", "--count", "2",
                 "--timeout", "30"],
                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
            )  # fmt: skip
            stdout, listen_log = listener.communicate(timeout=60)
            daemon.send_signal(signal.SIGTERM)
            assert daemon.wait(timeout=30) == 0
            lines += daemon_log.rest()
        finally:
            stop_process(daemon)
            if listener is not None:
                stop_process(listener)
    printed = stdout.splitlines()
    assert "alive  meet joined" in printed, stdout
    assert any(line.startswith("ALERT  meet #0 long_distraction warning") for line in printed)
    assert listener.returncode == 0, listen_log
    assert f"connecting to {endpoint(port)}" in listen_log
    daemon_text = "\n".join(lines)
    if with_router:
        assert f"connecting to {endpoint(port)}" in daemon_text
        assert connected_alone and "zenoh connected: router" in daemon_text
    else:
        assert f"listening on {endpoint(port)}" in daemon_text
        assert not connected_alone  # nobody there yet: no "connected"
        assert "zenoh connected: client" in daemon_text
