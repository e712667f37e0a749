"""Where a run may write: never onto a file it reads, never two outputs on one file.

`check_output_paths` runs before anything is opened or written; a refusal is one `ConfigError`.
Two paths are one file when they have the same real path (every symbolic link followed) or, when
both exist, the same device and inode (a hard link, or a second name the real path does not
show, e.g. a bind mount).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from roadgaze.errors import ConfigError

PathLike = str | Path

PLOT_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg", ".webp", ".tif", ".tiff")
"""File types matplotlib writes (a plot is saved at the end: a bad name must fail at the start)."""


def same_file(first: PathLike, second: PathLike) -> bool:
    """True when `first` and `second` name one file (see the module doc)."""
    try:
        if Path(first).resolve() == Path(second).resolve():
            return True
        one, other = Path(first).stat(), Path(second).stat()
    except (OSError, ValueError, RuntimeError):  # not there (yet), a NUL, a symlink loop
        return False
    return (one.st_dev, one.st_ino) == (other.st_dev, other.st_ino)


def inside(path: PathLike, folder: PathLike) -> bool:
    """True when `path` is in `folder` or below it (real paths)."""
    try:
        real, top = Path(path).resolve(), Path(folder).resolve()
    except (OSError, ValueError, RuntimeError):
        return False
    return real != top and real.is_relative_to(top)


def check_output_paths(
    inputs: Mapping[str, PathLike | None],
    outputs: Mapping[str, PathLike | None],
    suffixes: Mapping[str, tuple[str, ...]] | None = None,
    folders: Mapping[str, PathLike | None] | None = None,
) -> None:
    """Refuse, before anything is written, an output that is an input (it would destroy it),
    an output folder holding an input (its old files are pruned), two outputs on one file
    (they would mix formats) and an output whose file type its writer cannot write. Keys are
    the names used in the message (an option, or what the input is); '-' is stdout, None none.
    """
    read = {name: Path(path) for name, path in inputs.items() if path not in (None, "-")}
    given = {name: Path(path) for name, path in outputs.items() if path not in (None, "-")}
    for name, path in given.items():
        allowed = (suffixes or {}).get(name)
        if allowed and path.suffix.lower() not in allowed:
            raise ConfigError(
                f"{name} {path}: cannot write a {path.suffix or 'suffix-less'} file; "
                f"use {', '.join(allowed)}"
            )
        for input_name, input_path in read.items():
            if same_file(path, input_path):
                raise ConfigError(
                    f"{name} {path} is the input ({input_name}): it would be overwritten; "
                    "choose another output path"
                )
    for name, folder in (folders or {}).items():
        for input_name, input_path in read.items():
            if folder is not None and inside(input_path, folder):
                raise ConfigError(
                    f"{name} {folder} holds the input {input_path} ({input_name}): a recording "
                    "there is pruned to its size limit; choose another folder"
                )
    names = list(given)
    for index, name in enumerate(names):
        for other in names[index + 1 :]:
            if same_file(given[name], given[other]):
                raise ConfigError(
                    f"{name} and {other} are the same file {given[name]}; give each its own path"
                )
