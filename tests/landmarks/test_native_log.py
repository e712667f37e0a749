"""MediaPipe's native lines on fd 2: noise dropped, the rest as log records, so `--log-json`
stays one JSON object per line; roadgaze's own lines written meanwhile pass unchanged."""

from __future__ import annotations

import json
import logging
import os

import pytest

from roadgaze.landmarks.native_log import filtered_native_stderr
from roadgaze.logs import setup_logging


@pytest.mark.parametrize("json_format", [True, False], ids=["json", "text"])
def test_native_lines_become_log_records(
    capfd: pytest.CaptureFixture[str], json_format: bool
) -> None:
    setup_logging("INFO", json_format=json_format)
    with filtered_native_stderr():
        os.write(2, b"W0000 00:00:1764650000.1 42 inference_feedback_manager.cc:114] noise\n")
        os.write(2, b"INFO: Created TensorFlow Lite XNNPACK delegate for CPU.\n")
        os.write(2, b"E0000 00:00:1764650000.2 42 gl_context_egl.cc:85] Failed to get EGL\n")
        os.write(2, b"some library said this\n")
        logging.getLogger("roadgaze.test").info("our own line")  # another thread's log
        theirs = '{"time": "2026-12-02T06:00:00.000Z", "level": "INFO", "message": "our own line"}'
        os.write(2, f"{theirs}\n".encode())  # one that reached fd 2: passed on as it was
    lines = capfd.readouterr().err.splitlines()
    own = [line for line in lines if "our own line" in line]
    lines = [line for line in lines if line not in own]
    assert len(own) == 2 and len(lines) == 2
    assert theirs in own
    if json_format:
        logged = [line for line in own if line != theirs]
        records = [json.loads(line) for line in [*lines, *logged]]  # every line is JSON
        assert [(r["level"], r["logger"]) for r in records] == [
            ("ERROR", "roadgaze.native"),
            ("WARNING", "roadgaze.native"),
            ("INFO", "roadgaze.test"),
        ]
        assert records[0]["message"].endswith("gl_context_egl.cc:85] Failed to get EGL")
    else:
        assert " ERROR roadgaze.native: E0000 " in lines[0]
        assert lines[1].endswith("WARNING roadgaze.native: some library said this")
        assert any(line.endswith("INFO roadgaze.test: our own line") for line in own)
