"""The command line: errors end in one line and an exit code, never a traceback."""

from __future__ import annotations

import subprocess
import sys

import pytest

import roadgaze.evaluation.paper
from roadgaze.cli import main
from roadgaze.errors import ConfigError


def test_user_errors_print_one_line_and_exit_2(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def broken() -> None:
        raise ConfigError("geometry.beta: must be > 1 (found 0.5)")

    monkeypatch.setattr(roadgaze.evaluation.paper, "experiment_1", broken)
    assert main(["paper-tables"]) == 2
    err = capsys.readouterr().err
    assert err == "roadgaze paper-tables: error: geometry.beta: must be > 1 (found 0.5)\n"


def test_unknown_command_is_a_usage_error() -> None:
    with pytest.raises(SystemExit) as caught:
        main(["no-such-command"])
    assert caught.value.code == 2


def test_module_entry_point_prints_help_quickly(subprocess_env: dict[str, str]) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "roadgaze", "--help"],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
        env=subprocess_env,
    )
    assert result.returncode == 0
    assert "paper-tables" in result.stdout
    # --help must not import the heavy stages.
    probe = subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys, roadgaze.cli as c; c.build_parser(); "
            "print(sorted(m for m in ('mediapipe', 'zenoh', 'matplotlib') if m in sys.modules))",
        ],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
        env=subprocess_env,
    )
    assert probe.stdout.strip() == "[]"
