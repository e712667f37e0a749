"""docker/Dockerfile against .dockerignore: every file a `COPY` takes from the build context is
sent with it. (0.2.1's image stopped building: the Dockerfile copied constraints.txt, which
.dockerignore filtered out, and nothing built the image.)"""

from __future__ import annotations

import re
import shlex
import subprocess

import pytest

from repo_paths import REPO

DOCKERFILE = REPO / "docker" / "Dockerfile"
DOCKERIGNORE = REPO / ".dockerignore"


def _pattern_regex(pattern: str) -> re.Pattern[str]:
    """A .dockerignore pattern as a regular expression over slash-separated paths (Go's
    filepath.Match, plus `**` for any number of folders, as Docker's pattern matcher)."""
    out, index = [], 0
    while index < len(pattern):
        if pattern.startswith("**/", index):
            out.append("(?:.*/)?")
            index += 3
        elif pattern.startswith("**", index):
            out.append(".*")
            index += 2
        elif pattern[index] == "*":
            out.append("[^/]*")
            index += 1
        elif pattern[index] == "?":
            out.append("[^/]")
            index += 1
        else:
            out.append(re.escape(pattern[index]))
            index += 1
    return re.compile("".join(out) + r"\Z")


def _rules(text: str) -> list[tuple[bool, re.Pattern[str]]]:
    rules = []
    for line in text.splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        negated = line.startswith("!")
        pattern = line.removeprefix("!").strip().strip("/")
        rules.append((negated, _pattern_regex(pattern)))
    return rules


def excluded(path: str, rules: list[tuple[bool, re.Pattern[str]]]) -> bool:
    """Whether Docker leaves `path` out of the build context: the last rule that matches the
    path or one of its parent folders decides."""
    parts = path.split("/")
    candidates = ["/".join(parts[: i + 1]) for i in range(len(parts))]
    verdict = False
    for negated, regex in rules:
        if any(regex.match(candidate) for candidate in candidates):
            verdict = not negated
    return verdict


def context_sources() -> list[str]:
    """The build-context sources of every `COPY` (not `COPY --from=`) in the Dockerfile."""
    sources = []
    text = DOCKERFILE.read_text(encoding="utf-8").replace("\\\n", " ")
    for line in text.splitlines():
        words = shlex.split(line.strip(), comments=True) if line.strip() else []
        if not words or words[0].upper() not in ("COPY", "ADD"):
            continue
        arguments = words[1:]
        if any(word.startswith("--from") for word in arguments):
            continue
        paths = [word for word in arguments if not word.startswith("--")]
        sources.extend(path.removeprefix("./").rstrip("/") for path in paths[:-1])
    return sources


def tracked_files_under(source: str) -> list[str]:
    done = subprocess.run(
        ["git", "-C", str(REPO), "ls-files", "--", source],
        capture_output=True,
        text=True,
        check=False,
    )
    return done.stdout.splitlines() if done.returncode == 0 else []


@pytest.mark.parametrize(
    ("path", "expected"),
    [
        ("constraints.txt", True),  # under `*` alone
        ("src/roadgaze/cli.py", False),  # re-included by `!src`
        ("src/roadgaze/__pycache__/cli.cpython-311.pyc", True),
        (".git/HEAD", True),
    ],
)
def test_the_matcher_reads_patterns_as_docker_does(path: str, expected: bool) -> None:
    rules = _rules("*\n!src\n**/__pycache__\n")
    assert excluded(path, rules) is expected


def test_every_copy_source_of_the_dockerfile_is_in_the_build_context() -> None:
    rules = _rules(DOCKERIGNORE.read_text(encoding="utf-8"))
    sources = context_sources()
    assert "constraints.txt" in sources and "src" in sources
    for source in sources:
        assert (REPO / source).exists(), f"COPY {source}: not in the repository"
        assert not excluded(source, rules), f"COPY {source}: left out by .dockerignore"
        for tracked in tracked_files_under(source):
            assert not excluded(tracked, rules), f"COPY {source}: {tracked} left out"
