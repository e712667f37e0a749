"""MCAP read in memory bounded by `record.max_chunk_mib`, not by the file: a chunk that declares
more is refused before it is decompressed (replay, bench and recover, one line, exit 2), a chunk
that holds more than it declares is damaged (read up to it), and ordinary chunks read as before.

The files here claim large sizes but hold little, so the tests allocate nothing large: a reader
that trusted the claim would not fail, it would just not refuse."""

from __future__ import annotations

import base64
import json
import struct
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
import zstandard
from mcap.writer import Writer

from repo_paths import child_env
from roadgaze.capture import McapSource
from roadgaze.errors import SourceError
from roadgaze.outputs.foxglove.recover import recover_mcap

MIB = 1 << 20
GREY = np.full((120, 160, 3), 128, np.uint8)


def camera_message(channel_id: int, log_ns: int, data: bytes) -> bytes:
    """One MCAP Message record (opcode 5), as a chunk holds it."""
    body = struct.pack("<HIQQ", channel_id, 0, log_ns, log_ns) + data
    return struct.pack("<BQ", 0x05, len(body)) + body


def jpeg_payload() -> bytes:
    ok, data = cv2.imencode(".jpg", GREY)
    assert ok
    return json.dumps(
        {"format": "jpeg", "data": base64.b64encode(data.tobytes()).decode()}
    ).encode()


def crafted_mcap(path: Path, content_bytes: int, declared: int | None = None) -> Path:
    """A recording of three camera frames: one outside any chunk, then a zstd chunk of one
    message padded to `content_bytes` (a picture that does not decode), declaring `declared`
    bytes uncompressed (default: the truth), then one more frame outside."""
    good = jpeg_payload()
    with path.open("wb") as handle:
        writer = Writer(handle, use_chunking=False)
        writer.start()
        schema_id = writer.register_schema("foxglove.CompressedImage", "jsonschema", b"{}")
        channel_id = writer.register_channel("/camera/image", "json", schema_id)
        writer.add_message(channel_id, 0, good, 0)
        content = camera_message(channel_id, 100_000_000, b"x" * max(0, content_bytes - 31))
        data = zstandard.ZstdCompressor().compress(content)
        size = len(content) if declared is None else declared
        body = (
            struct.pack("<QQQI", 100_000_000, 100_000_000, size, 0)
            + struct.pack("<I", 4)
            + b"zstd"
            + struct.pack("<Q", len(data))
            + data
        )
        handle.write(struct.pack("<BQ", 0x06, len(body)) + body)
        writer.add_message(channel_id, 200_000_000, good, 200_000_000)
        writer.finish()
    return path


def test_a_chunk_within_the_limit_reads_as_before(tmp_path: Path) -> None:
    path = crafted_mcap(tmp_path / "ok.mcap", 2 * MIB)
    with McapSource(path, max_chunk_mib=4) as source:
        frames = list(source)
        assert source.status.frames_skipped == 1  # the padded picture does not decode
    assert [frame.t_s for frame in frames] == pytest.approx([0.0, 0.2])


def test_a_chunk_that_declares_more_than_the_limit_is_refused_unread(tmp_path: Path) -> None:
    path = crafted_mcap(tmp_path / "claims.mcap", 1000, declared=768 * MIB)
    with pytest.raises(SourceError) as caught, McapSource(path) as source:
        list(source)
    assert str(caught.value) == (
        f"MCAP recording {path}: a chunk declares 768.0 MiB uncompressed, above "
        "record.max_chunk_mib (32 MiB), the memory a chunk may take; not read. If the recording "
        "is genuine, raise the limit, e.g. --set record.max_chunk_mib=256"
    )
    with pytest.raises(SourceError, match=r"declares 768\.0 MiB"):
        recover_mcap(path, tmp_path / "recovered.mcap")
    assert not (tmp_path / "recovered.mcap").exists()
    with McapSource(path, max_chunk_mib=1024) as source:  # the setting lets it be read ...
        assert len(list(source)) == 1  # ... and found to hold less than it declares
        assert "a chunk that declares 805306368 bytes holds 1000" in str(source.status.message)


def test_a_chunk_that_holds_more_than_it_declares_is_damaged(tmp_path: Path) -> None:
    """zstd announces the content's size in its own frame header and allocates that much,
    whatever the chunk declares: a chunk whose frame announces more is damaged, read up to."""
    path = crafted_mcap(tmp_path / "liar.mcap", 4 * MIB, declared=1000)
    with McapSource(path) as source:
        frames = list(source)
        status = source.status
    assert len(frames) == 1 and status.truncated
    assert "a chunk that declares 1000 bytes holds 4194304" in str(status.message)


@pytest.mark.parametrize("command", ["replay", "bench", "recover"])
def test_each_command_refuses_a_chunk_above_the_limit_in_one_line(
    tmp_path: Path, command: str
) -> None:
    path = crafted_mcap(tmp_path / "claims.mcap", 1000, declared=768 * MIB)
    args = {"replay": ["--no-progress"], "bench": ["--no-raw", "--warmup", "0"], "recover": []}
    result = subprocess.run(
        [sys.executable, "-m", "roadgaze", command, str(path), *args[command]],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=300,
        check=False,
        cwd=tmp_path,
    )
    assert result.returncode == 2, result.stderr[-2000:]
    last = result.stderr.strip().splitlines()[-1]
    assert last.startswith(f"roadgaze {command}: error: MCAP recording {path}: a chunk declares")
    assert "Traceback" not in result.stderr


def test_a_record_cut_by_kill_9_is_a_cut_file_not_a_refusal(tmp_path: Path) -> None:
    """A writer killed inside a record can leave a length field that claims far more than the
    file holds (all ones, as a placeholder): that is a recording cut short, read up to there
    and recoverable, not a chunk above the limit."""
    from mcap.reader import make_reader

    whole = tmp_path / "whole.mcap"
    with whole.open("wb") as handle:
        writer = Writer(handle, chunk_size=4096)
        writer.start()
        schema_id = writer.register_schema("foxglove.CompressedImage", "jsonschema", b"{}")
        channel_id = writer.register_channel("/camera/image", "json", schema_id)
        for index in range(12):
            writer.add_message(channel_id, index * 100_000_000, jpeg_payload(), 0)
        writer.finish()
    with whole.open("rb") as handle:
        summary = make_reader(handle).get_summary()
    assert summary is not None
    last_chunk = max(index.chunk_start_offset for index in summary.chunk_indexes)
    cut = tmp_path / "cut.mcap.part"
    cut.write_bytes(whole.read_bytes()[:last_chunk] + b"\x06" + b"\xff" * 8 + b"half a chunk")
    with McapSource(cut) as source:
        frames = list(source)
        status = source.status
    assert 0 < len(frames) < 12 and status.truncated
    assert "cut inside a record that claims 18446744073709551615 bytes" in str(status.message)
    recovery = recover_mcap(cut, tmp_path / "cut.mcap")
    assert recovery.messages == len(frames) and recovery.bytes_read == last_chunk
