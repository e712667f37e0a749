"""A recording cut short made whole: `run --record` killed with `kill -9` (a real daemon process
with a scripted camera and detector), every closed segment readable, the open one recovered
with the `mcap` reader up to its last complete chunk (at most `record.flush_s` lost); files cut
at any byte; `roadgaze recover`; the MCAP frame source reading a cut file."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from foxglove_helpers import pipeline_records, read_mcap
from repo_paths import REPO, child_env
from roadgaze.capture import McapSource
from roadgaze.cli import main
from roadgaze.config import Config, RecordConfig
from roadgaze.errors import RoadgazeError
from roadgaze.outputs.foxglove.channels import TOPIC_RECORD, TOPIC_STATE
from roadgaze.outputs.foxglove.open import replay_recorder
from roadgaze.outputs.foxglove.recover import recover_mcap, recover_parts
from zenoh_helpers import endpoint, free_port, stop_process, wait_for

FAKE_DAEMON = REPO / "tests" / "fake_daemon.py"
FLUSH_S = 0.5


def frames_of(path: Path) -> list[int]:
    return [record["frame"] for record in read_mcap(path).json(TOPIC_RECORD)]


def test_kill_9_leaves_closed_segments_readable_and_the_open_one_recoverable(
    tmp_path: Path,
) -> None:
    folder = tmp_path / "rec"
    settings = [
        "--set",
        "record.images=true",
        "--set",
        f"record.flush_s={FLUSH_S}",
        "--set",
        "record.segment_s=2",
        "--set",
        "record.state_interval_s=0.25",
    ]
    daemon = subprocess.Popen(
        [
            sys.executable,
            str(FAKE_DAEMON),
            "--record",
            str(folder),
            *settings,
            "--zenoh-listen",
            endpoint(free_port()),
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env=child_env(),
    )
    try:

        def part_written() -> bool:
            parts = list(folder.glob("*.mcap.part"))
            closed = list(folder.glob("*.mcap"))
            return len(closed) >= 2 and bool(parts) and parts[0].stat().st_size > 20_000

        assert wait_for(part_written, timeout_s=90.0), daemon.stderr.read() if daemon.poll() else ""
        daemon.send_signal(signal.SIGKILL)
        killed_s = time.time()
        daemon.wait(timeout=10.0)
    finally:
        stop_process(daemon)
    assert daemon.returncode == -signal.SIGKILL
    closed = sorted(folder.glob("*.mcap"))
    (part,) = folder.glob("*.mcap.part")
    frames = [frames_of(path) for path in closed]
    for segment in frames:
        assert segment == list(range(segment[0], segment[0] + len(segment)))
    recovered = recover_mcap(part, tmp_path / "recovered.mcap")
    # The kill may land between two chunks (nothing half-written: "end of file") or inside one
    # (the half-written chunk is what is lost); either way the part has no footer of its own.
    assert recovered.messages > 0
    assert recovered.bytes_read + recovered.bytes_lost == part.stat().st_size
    part_frames = frames_of(recovered.path)
    everything = [frame for segment in [*frames, part_frames] for frame in segment]
    assert everything == list(range(everything[0], everything[0] + len(everything)))
    # Lost: the chunk being written, i.e. at most one flush interval (and the state's own
    # interval, a frame's time and the kill's scheduling on a loaded machine).
    states = read_mcap(recovered.path).json(TOPIC_STATE)
    assert killed_s - states[-1]["wall_time"] <= FLUSH_S + 0.25 + 1.5
    with McapSource(part) as source:
        seen = [frame.index for frame in source]
        assert source.status.truncated and "cut short" in (source.status.message or "")
    assert len(seen) == read_mcap(recovered.path).counts["/camera/image"]


@pytest.fixture(scope="module")
def complete(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("whole") / "drive.mcap"
    config = Config(record=RecordConfig(chunk_kb=16, image_fps=30.0))
    with replay_recorder(config, "numbered", path) as recorder:
        for record, frame in pipeline_records():
            recorder.on_record(record, frame)
    return path


@pytest.mark.parametrize("fraction", [0.35, 0.5, 0.8, 0.97])
def test_a_file_cut_at_any_byte_keeps_every_complete_chunk(
    complete: Path, tmp_path: Path, fraction: float
) -> None:
    data = complete.read_bytes()
    cut = tmp_path / "cut.mcap.part"
    cut.write_bytes(data[: int(len(data) * fraction)])
    recovery = recover_mcap(cut, tmp_path / "whole.mcap")
    frames = frames_of(recovery.path)
    assert frames == list(range(len(frames)))
    total = sum(read_mcap(complete).counts.values())
    if fraction < 0.9:
        assert 0 < recovery.messages < total
    else:  # cut in the summary: every message kept
        assert recovery.messages == total and len(frames) == 210
    assert recovery.bytes_read + recovery.bytes_lost == cut.stat().st_size
    # Nothing read is lost: a longer cut keeps at least as much.
    longer = tmp_path / "longer.mcap.part"
    longer.write_bytes(data[: int(len(data) * min(1.0, fraction + 0.02))])
    assert len(frames_of(recover_mcap(longer, tmp_path / "longer.mcap").path)) >= len(frames)


def test_a_whole_file_recovers_to_the_same_messages(complete: Path, tmp_path: Path) -> None:
    recovery = recover_mcap(complete, tmp_path / "again.mcap")
    assert recovery.stopped_because == "end of file" and recovery.bytes_lost == 0
    before, after = read_mcap(complete), read_mcap(recovery.path)
    assert after.counts == before.counts and after.schemas == before.schemas
    assert after.json(TOPIC_RECORD) == before.json(TOPIC_RECORD)
    assert after.metadata == before.metadata


def test_something_that_is_not_mcap_is_one_line(tmp_path: Path) -> None:
    other = tmp_path / "notes.mcap.part"
    other.write_bytes(b"hello world, not a recording at all")
    with pytest.raises(RoadgazeError, match=r"is not an MCAP recording"):
        recover_mcap(other, tmp_path / "notes.mcap")
    assert not (tmp_path / "notes.mcap").exists()


def test_the_recover_command(
    complete: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], restore_logging: None
) -> None:
    data = complete.read_bytes()
    part = tmp_path / "drive.mcap.part"
    part.write_bytes(data[: len(data) // 2])
    assert main(["recover", str(part)]) == 0
    err = capsys.readouterr().err
    assert "messages in" in err and "kept; lost" in err and "wrote" in err
    frames = frames_of(tmp_path / "drive.mcap")
    assert frames == list(range(len(frames)))
    assert main(["recover", str(part), "--out", str(part)]) == 2
    assert "cannot write a .part file; use .mcap" in capsys.readouterr().err
    whole = tmp_path / "drive.mcap"
    assert main(["recover", str(whole), "--out", str(whole)]) == 2
    assert "is the input (FILE)" in capsys.readouterr().err


def test_recover_never_overwrites_another_recording(
    complete: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], restore_logging: None
) -> None:
    """`X.mcap.part` beside another, different `X.mcap`: the recovery takes the next free name
    (said in one warning), again and again; an --out that exists is refused in one line."""
    data = complete.read_bytes()
    part = tmp_path / "X.mcap.part"
    part.write_bytes(data[: len(data) // 2])
    other = tmp_path / "X.mcap"
    other.write_bytes(b"another recording, kept byte for byte")
    assert main(["recover", str(part)]) == 0
    err = capsys.readouterr().err
    assert f"{other} exists (another file, never overwritten): wrote {tmp_path / 'X-1.mcap'}" in err
    assert other.read_bytes() == b"another recording, kept byte for byte"
    assert sum(read_mcap(tmp_path / "X-1.mcap").counts.values()) > 0
    assert main(["recover", str(part)]) == 0
    assert (tmp_path / "X-2.mcap").read_bytes() == (tmp_path / "X-1.mcap").read_bytes()
    capsys.readouterr()
    assert main(["recover", str(part), "--out", str(other)]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"roadgaze recover: error: {other} exists; recover never overwrites a file: remove it "
        "or choose another --out"
    ]
    assert other.read_bytes() == b"another recording, kept byte for byte"
    assert sorted(path.name for path in tmp_path.iterdir()) == [
        "X-1.mcap",
        "X-2.mcap",
        "X.mcap",
        "X.mcap.part",
    ]


def test_run_record_recovers_a_part_beside_a_closed_segment_of_its_name(
    complete: Path, tmp_path: Path
) -> None:
    data = complete.read_bytes()
    (tmp_path / "seg-1.mcap.part").write_bytes(data[: len(data) // 2])
    (tmp_path / "seg-1.mcap").write_bytes(data)
    (recovery,) = recover_parts(tmp_path, "seg-*.mcap.part")
    assert recovery.path == tmp_path / "seg-1-1.mcap"
    assert (tmp_path / "seg-1.mcap").read_bytes() == data
    assert not (tmp_path / "seg-1.mcap.part").exists()


def test_the_mcap_source_reads_a_cut_file_up_to_its_last_chunk(
    complete: Path, tmp_path: Path
) -> None:
    data = complete.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    with McapSource(complete) as whole:
        all_frames = [(frame.t_s, frame.image) for frame in whole]
    with McapSource(cut) as source:
        frames = [(frame.t_s, frame.image) for frame in source]
        status = source.status
    assert 0 < len(frames) < len(all_frames) and status.truncated
    for (t_s, image), (whole_t_s, whole_image) in zip(frames, all_frames, strict=False):
        assert t_s == whole_t_s and np.array_equal(image, whole_image)
    assert json.dumps(status.message).count("cut short") == 1


def test_a_file_that_ends_after_a_whole_chunk_is_still_cut_short(
    complete: Path, tmp_path: Path
) -> None:
    """`kill -9` just after a chunk was written leaves no half record, but no footer either:
    the MCAP source reads every frame up to there and says the file is cut short."""
    data = complete.read_bytes()
    probe = tmp_path / "probe.mcap.part"
    probe.write_bytes(data[: len(data) // 2])
    boundary = recover_mcap(probe, tmp_path / "probe.mcap").bytes_read
    cut = tmp_path / "boundary.mcap.part"
    cut.write_bytes(data[:boundary])
    recovery = recover_mcap(cut, tmp_path / "boundary.mcap")
    assert recovery.bytes_lost == 0
    with McapSource(cut) as source:
        seen = [frame.index for frame in source]
        assert source.status.truncated and "cut short" in (source.status.message or "")
    assert len(seen) == read_mcap(recovery.path).counts["/camera/image"] > 0
    with McapSource(complete) as source:
        assert len(list(source)) > len(seen) and not source.status.truncated
