"""An MCAP recording as a drive: the camera channel's frames with their own stamps (roadgaze's
time offset taken off again), `foxglove.CompressedImage` and `foxglove.RawImage` in protobuf or
JSON, the channel chosen or asked for, damaged frames skipped, and the source picked by
`open_source` from the file's magic bytes."""

from __future__ import annotations

import base64
import json
import logging
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest
from mcap.writer import Writer

from fakes import ScriptedDetector, numbered_image
from foxglove_helpers import pipeline_records
from repo_paths import child_env
from roadgaze.capture import McapSource, VideoFileSource, is_mcap, open_source
from roadgaze.capture.mcap_images import decode_raw
from roadgaze.config import Config, RecordConfig
from roadgaze.errors import SourceError
from roadgaze.outputs.foxglove.open import replay_recorder, vehicle_recorder
from roadgaze.pipeline import Pipeline

RECORDS = pipeline_records()[:40]
COMPRESSED = "foxglove.CompressedImage"
PNG_EVERY_FRAME = RecordConfig(image_format="png", image_fps=1000.0, flush_s=0.05)


def recorded(path: Path, wall_clock: bool = False) -> Path:
    config = Config(record=PNG_EVERY_FRAME.model_copy(update={"images": True}))
    if wall_clock:
        recorder = vehicle_recorder(config, "numbered", path.parent, None)
        # The vehicle's recorder drops a camera frame its image thread is behind on (a loaded
        # machine dropped 2 of 40 at a camera's pace); these tests read every frame back.
        recorder.block_on_images = True
    else:
        recorder = replay_recorder(config, "numbered", path)
    with recorder:
        for record, frame in RECORDS:
            recorder.on_record(record, frame)
            if wall_clock:
                time.sleep(0.02)  # a camera's pace
    return path if not wall_clock else next(path.parent.glob("*.mcap"))


def test_a_replay_recording_gives_back_every_frame_and_its_time(tmp_path: Path) -> None:
    path = recorded(tmp_path / "drive.mcap")
    with McapSource(path) as source:
        frames = list(source)
        assert source.info.frame_count == len(RECORDS) and source.info.live is False
        assert source.info.fps == pytest.approx(30.0, rel=1e-6)
        assert (source.info.width, source.info.height) == (160, 120)
        assert source.status.ended and not source.status.truncated
    assert [frame.index for frame in frames] == list(range(len(RECORDS)))
    for frame, (record, original) in zip(frames, RECORDS, strict=True):
        assert frame.t_s == pytest.approx(record.t_s, abs=1e-9)
        assert np.array_equal(frame.image, original.image)  # PNG: lossless


def test_a_vehicle_recording_replays_on_the_source_timeline(tmp_path: Path) -> None:
    path = recorded(tmp_path / "run" / "x.mcap", wall_clock=True)
    with McapSource(path) as source:
        assert source.offset_ns is not None and source.offset_ns > 1e18  # wall clock, in 2026
        times = [frame.t_s for frame in source]
    assert times == pytest.approx([record.t_s for record, _ in RECORDS], abs=1e-9)


def foreign_mcap(
    path: Path,
    channels: dict[str, tuple[str, list[bytes]]],
    metadata: dict[str, str] | None = None,
) -> Path:
    """An MCAP written with the `mcap` package (no roadgaze metadata unless `metadata` gives the
    `roadgaze` record's): JSON image channels, one message per 1/10 s from t = 1000 s, header
    stamps 5 ms after the log times."""
    with path.open("wb") as handle:
        writer = Writer(handle)
        writer.start()
        if metadata is not None:
            writer.add_metadata("roadgaze", metadata)
        for topic, (schema_name, payloads) in channels.items():
            schema_id = writer.register_schema(schema_name, "jsonschema", b"{}")
            channel_id = writer.register_channel(topic, "json", schema_id)
            for index, payload in enumerate(payloads):
                log_ns = 1_000_000_000_000 + index * 100_000_000
                writer.add_message(channel_id, log_ns, payload, log_ns)
        writer.finish()
    return path


def _stamped(index: int, ahead_s: int = 0, **fields: object) -> bytes:
    stamp_ns = 1_000_000_000_000 + index * 100_000_000 + 5_000_000 + ahead_s * 10**9
    stamp = {"sec": stamp_ns // 10**9, "nsec": stamp_ns % 10**9}
    return json.dumps({"timestamp": stamp, "frame_id": "cam", **fields}).encode()


def compressed(index: int, image: np.ndarray, fmt: str = "jpeg", ahead_s: int = 0) -> bytes:
    ok, data = cv2.imencode(".png" if fmt == "png" else ".jpg", image)
    assert ok
    return _stamped(index, ahead_s, data=base64.b64encode(data.tobytes()).decode(), format=fmt)


def raw(index: int, image: np.ndarray, encoding: str) -> bytes:
    height, width = image.shape[:2]
    step = image.strides[0]
    return _stamped(
        index,
        width=width,
        height=height,
        encoding=encoding,
        step=step,
        data=base64.b64encode(image.tobytes()).decode(),
    )


def test_a_foreign_recording_starts_at_its_first_frame_and_uses_header_stamps(
    tmp_path: Path,
) -> None:
    images = [RECORDS[i][1].image for i in range(5)]
    messages = [compressed(i, image, "png") for i, image in enumerate(images)]
    path = foreign_mcap(tmp_path / "foreign.mcap", {"/cam/front": (COMPRESSED, messages)})
    with McapSource(path) as source:
        frames = list(source)
        assert source.offset_ns is None and source.topic == "/cam/front"
    assert [frame.t_s for frame in frames] == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4], abs=1e-9)
    assert all(np.array_equal(f.image, im) for f, im in zip(frames, images, strict=True))


@pytest.mark.parametrize("encoding", ["rgb8", "bgr8", "mono8", "mono16", "rgba8", "bgra8"])
def test_raw_images_of_each_encoding(tmp_path: Path, encoding: str) -> None:
    bgr = RECORDS[3][1].image
    pixels = {
        "rgb8": cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB),
        "bgr8": bgr,
        "mono8": bgr[:, :, 0].copy(),
        "mono16": bgr[:, :, 0].astype(np.uint16) * 256,
        "rgba8": cv2.cvtColor(bgr, cv2.COLOR_BGR2RGBA),
        "bgra8": cv2.cvtColor(bgr, cv2.COLOR_BGR2BGRA),
    }[encoding]
    path = foreign_mcap(
        tmp_path / "raw.mcap", {"/raw": ("foxglove.RawImage", [raw(0, pixels, encoding)])}
    )
    with McapSource(path) as source:
        (frame,) = list(source)
    expected = (
        bgr
        if encoding in ("rgb8", "bgr8", "rgba8", "bgra8")
        else cv2.cvtColor(bgr[:, :, 0].copy(), cv2.COLOR_GRAY2BGR)
    )
    assert np.array_equal(frame.image, expected)


def test_raw_image_rows_with_padding() -> None:
    image = np.arange(3 * 5, dtype=np.uint8).reshape(3, 5)
    padded = np.zeros((3, 8), np.uint8)
    padded[:, :5] = image
    decoded = decode_raw(5, 3, "mono8", 8, padded.tobytes())
    assert np.array_equal(decoded[:, :, 0], image)
    with pytest.raises(SourceError, match="holds 10 bytes"):
        decode_raw(5, 3, "mono8", 8, padded.tobytes()[:10])
    with pytest.raises(SourceError, match="encoding 'yuv422' is not read"):
        decode_raw(5, 3, "yuv422", 10, padded.tobytes())


def test_two_camera_channels_need_a_choice(tmp_path: Path) -> None:
    image = RECORDS[0][1].image
    path = foreign_mcap(
        tmp_path / "two.mcap",
        {
            "/cam/driver": ("foxglove.CompressedImage", [compressed(0, image)]),
            "/cam/road": ("foxglove.CompressedImage", [compressed(0, image), compressed(1, image)]),
        },
    )
    found = r"\(image channels: /cam/driver, /cam/road\); name one with --set record\.camera_topic"
    with pytest.raises(SourceError, match=r"no camera channel /camera/image " + found):
        McapSource(path)
    with McapSource(path, topic="/cam/road") as source:
        assert source.info.frame_count == 2 and len(list(source)) == 2
    config = Config(record=RecordConfig(camera_topic="/cam/driver"))
    with open_source(str(path), config) as source:
        assert isinstance(source, McapSource) and source.topic == "/cam/driver"


def test_a_damaged_frame_is_skipped_and_counted(tmp_path: Path) -> None:
    image = RECORDS[0][1].image
    broken = _stamped(1, data=base64.b64encode(b"not a jpeg").decode(), format="jpeg")
    messages = [compressed(0, image), broken, compressed(2, image)]
    path = foreign_mcap(tmp_path / "damaged.mcap", {"/camera/image": (COMPRESSED, messages)})
    with McapSource(path) as source:
        frames = list(source)
        assert source.status.frames_skipped == 1
    assert [round(frame.t_s, 6) for frame in frames] == [0.0, 0.2]


def test_no_camera_frame_at_all_is_one_line(tmp_path: Path) -> None:
    path = foreign_mcap(tmp_path / "logs.mcap", {"/log": ("foxglove.Log", [b"{}"])})
    with pytest.raises(
        SourceError, match=r"has no camera channel /camera/image \(image channels: none\)"
    ):
        McapSource(path)


def test_open_source_tells_mcap_from_video_by_the_magic_bytes(tmp_path: Path) -> None:
    path = recorded(tmp_path / "drive.mcap")
    renamed = path.rename(tmp_path / "drive.bin")
    assert is_mcap(renamed)
    with open_source(str(renamed)) as source:
        assert isinstance(source, McapSource)
    video = tmp_path / "clip.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter.fourcc(*"MJPG"), 10, (160, 120))
    for _, frame in RECORDS[:3]:
        writer.write(frame.image)
    writer.release()
    assert not is_mcap(video)
    with open_source(str(video)) as source:
        assert isinstance(source, VideoFileSource)


def test_without_the_mcap_reader_an_mcap_drive_is_one_line(tmp_path: Path) -> None:
    path = recorded(tmp_path / "drive.mcap")
    code = (
        "import sys; sys.modules['mcap'] = None\n"
        "from roadgaze.cli import main\n"
        f"sys.exit(main(['replay', {str(path)!r}, '--no-progress']))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=120,
        check=False,
    )
    assert result.returncode == 2
    assert result.stderr.strip().splitlines()[-1] == (
        f"roadgaze replay: error: {path} is an MCAP recording; reading it needs the MCAP "
        "reader, which is not installed: pip install 'roadgaze[foxglove]'"
    )
    assert "Traceback" not in result.stderr


def test_a_frame_stamped_far_ahead_is_joined_and_raises_no_alert(tmp_path: Path) -> None:
    """One frame stamped 10^12 s ahead (a clock stepped on the vehicle, a hostile file), in the
    middle of a 1.5 s glance away: before, the glance lasted 10^12 s (long_distraction
    critical, vats, unresponsive). Now the clock is joined across it: the drive's own times,
    said once, and no alert from the real loop."""
    count, jump_at = 30, 15
    messages = [
        compressed(i, numbered_image(i), "png", ahead_s=10**12 if i == jump_at else 0)
        for i in range(count)
    ]
    path = foreign_mcap(tmp_path / "jump.mcap", {"/camera/image": (COMPRESSED, messages)})
    with McapSource(path) as source:
        times = [frame.t_s for frame in source]
        status = source.status
    assert times == pytest.approx([0.1 * i for i in range(count)], abs=1e-6)
    assert "its clock was joined across 2 breaks (the first: timestamps jump" in str(status.message)
    yaws: list[float | None] = [0.0] * 10 + [-60.0] * 15 + [0.0] * 5  # 1.5 s away
    pipeline = Pipeline.from_config(Config(), ScriptedDetector(yaws))
    with McapSource(path) as source:
        alerts = [alert.kind for done in pipeline.frames(source) for alert in done.record.alerts]
    assert alerts == []


@pytest.mark.parametrize(
    ("offset", "says"),
    [
        ("1" + "0" * 29, "lies outside MCAP's times"),
        ("-5", "lies outside MCAP's times"),
        ("1e9", "'1e9' is not an integer"),
        (str(2_000 * 10**9), "lies after its first frame's stamp"),
    ],
    ids=["1e29", "negative", "not-an-integer", "after-the-first-frame"],
)
def test_a_time_offset_that_is_no_time_is_said_and_ignored(
    tmp_path: Path, offset: str, says: str, caplog: pytest.LogCaptureFixture
) -> None:
    """A `time_offset_ns` of 1e29 ended in a traceback. The offset only places a drive on its
    source's timeline; the frames' own stamps still time it, so a bad one is ignored with one
    warning and the drive starts at its first frame, like a recording roadgaze did not write."""
    caplog.set_level(logging.WARNING)
    messages = [compressed(i, numbered_image(i), "png") for i in range(3)]
    path = foreign_mcap(
        tmp_path / "offset.mcap",
        {"/camera/image": (COMPRESSED, messages)},
        metadata={"time_offset_ns": offset},
    )
    with McapSource(path) as source:
        times = [frame.t_s for frame in source]
    assert times == pytest.approx([0.0, 0.1, 0.2], abs=1e-9)
    warnings = [r.getMessage() for r in caplog.records if r.levelname == "WARNING"]
    assert len(warnings) == 1 and "time_offset_ns" in warnings[0] and says in warnings[0]
    good = foreign_mcap(
        tmp_path / "good.mcap",
        {"/camera/image": (COMPRESSED, messages)},
        metadata={"time_offset_ns": str(999 * 10**9)},
    )
    with McapSource(good) as source:
        assert [frame.t_s for frame in source] == pytest.approx([1.005, 1.105, 1.205], abs=1e-9)


def test_a_raw_frame_of_the_wrong_size_is_skipped_and_counted(tmp_path: Path) -> None:
    """A RawImage whose bytes do not fill its width x height ended the replay; it is a bad
    frame like a JPEG that does not decode: skipped, logged, counted, said at the end."""
    image = RECORDS[0][1].image
    short = raw(1, image, "bgr8")
    message = json.loads(short)
    message["data"] = base64.b64encode(image.tobytes()[:1000]).decode()
    frames_in = [raw(0, image, "bgr8"), json.dumps(message).encode(), raw(2, image, "bgr8")]
    path = foreign_mcap(tmp_path / "raw.mcap", {"/raw": ("foxglove.RawImage", frames_in)})
    with McapSource(path) as source:
        frames = list(source)
        status = source.status
    assert [round(frame.t_s, 6) for frame in frames] == [0.0, 0.2]
    assert status.frames_skipped == 1
    assert "1 camera frame skipped (the first: RawImage of 160x120 bgr8 holds 1000 bytes)" in str(
        status.message
    )
    only_bad = foreign_mcap(
        tmp_path / "bad.mcap", {"/raw": ("foxglove.RawImage", [json.dumps(message).encode()])}
    )
    with pytest.raises(SourceError, match=r"no readable camera frame .*1 skipped: RawImage of"):
        McapSource(only_bad)
