"""Where a run may write: never onto a file it reads, never two outputs on one file.

`check_output_paths` runs before anything is opened or written; a refusal is one `ConfigError`.
Two paths are one file when they have the same real path (every symbolic link followed) or, when
both exist, the same device and inode (a hard link, or a second name the real path does not
show, e.g. a bind mount).
"""

from __future__ import annotations

import fnmatch
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


def _exists_but_not_a_file(path: Path) -> bool:
    try:
        return path.exists() and not path.is_file()
    except (OSError, ValueError):
        return False


def in_folder(path: PathLike, folder: PathLike, pattern: str) -> bool:
    """True when `path` is in `folder` (real paths) with a name matching `pattern` (fnmatch)."""
    try:
        real, top = Path(path).resolve(), Path(folder).resolve()
    except (OSError, ValueError, RuntimeError):
        return False
    return real.parent == top and fnmatch.fnmatch(real.name, pattern)


def check_output_paths(
    inputs: Mapping[str, PathLike | None],
    outputs: Mapping[str, PathLike | None],
    suffixes: Mapping[str, tuple[str, ...]] | None = None,
    folders: Mapping[str, tuple[PathLike | None, str]] | None = None,
) -> None:
    """Refuse, before anything is written, an output that is an input (it would destroy it),
    an input that an output folder's writer may remove or rename (`folders`: name -> (folder,
    the fnmatch pattern of the files it manages)), two outputs on one file (they would mix
    formats), an output that exists but is no regular file (`/dev/null` would be replaced by a
    file) and an output whose file type its writer cannot write. Keys are the names used in
    the message (an option, or what the input is); '-' is stdout, None none.
    """
    read = {name: Path(path) for name, path in inputs.items() if path not in (None, "-")}
    given = {name: Path(path) for name, path in outputs.items() if path not in (None, "-")}
    for name, path in given.items():
        if _exists_but_not_a_file(path):
            raise ConfigError(
                f"{name} {path} is not a regular file (a device, a pipe or a folder): outputs "
                "are written as files and completed in place (e.g. the offline columns are "
                "read back); give a file path, or '-' for stdout where the option takes it"
            )
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
    for name, (folder, pattern) in (folders or {}).items():
        for input_name, input_path in read.items():
            if folder is not None and in_folder(input_path, folder, pattern):
                raise ConfigError(
                    f"{name} {folder} would prune or recover the input {input_path} "
                    f"({input_name}): it is named as one of its files ({pattern}); "
                    "choose another folder"
                )
    names = list(given)
    for index, name in enumerate(names):
        for other in names[index + 1 :]:
            if same_file(given[name], given[other]):
                raise ConfigError(
                    f"{name} and {other} are the same file {given[name]}; give each its own path"
                )
