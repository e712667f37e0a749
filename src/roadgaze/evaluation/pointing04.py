"""Pointing'04 (the "Head Pose Image Database", Gourier, Hall and Crowley 2004) as an
evaluation set: images and the `ground_truth.csv` that `roadgaze eval` reads.

The public archive names every image `personne<PP><S><II><tilt><pan>.jpg` (some copies drop the
"ne": `person...`): PP the subject (01-15), S the series (1 or 2), II the image's index within the
series (00-92), then the tilt and the pan in degrees with their signs, e.g.
`personne01146+0+0.jpg` or `personne02215-30+45.jpg`. The labels are the directions of the
markers the subject looked at, in 15 deg steps (tilt also +-60 and +-90).

The archive's pan grows towards the image's left as the subject sees it (a pan of +45 has the
nose pointing to the image left), which is a turn to the subject's own right. roadgaze's yaw is
positive for a turn to the driver's own left (ISO 8855), so `yaw_deg = -pan`; `pitch_deg = tilt`
(positive looking up). Tilts of +-90 carry pan 0 and `roadgaze eval` skips them for yaw.
"""

from __future__ import annotations

import csv
import logging
import os
import re
import shutil
import stat
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from roadgaze.errors import ConfigError, DatasetError

log = logging.getLogger(__name__)

NAME_PATTERN = re.compile(
    r"^person(?:ne)?(?P<subject>\d{2})(?P<series>[12])(?P<index>\d{2})"
    r"(?P<tilt>[+-]\d{1,2})(?P<pan>[+-]\d{1,2})\.jpe?g$",
    re.IGNORECASE,
)
"""A Pointing'04 image name; the groups are the subject, series, index, tilt and pan."""

SUBJECTS = range(1, 16)
"""The archive's subjects, Person01 to Person15."""

COLUMNS = ("file", "yaw_deg", "pitch_deg", "pan_label", "tilt_label", "subject", "series")
"""The columns of the `ground_truth.csv` written (`roadgaze eval` needs `file` and `yaw_deg`;
`pitch_deg` adds the pitch and lap figures, `subject` the held-out-half checks)."""


@dataclass(frozen=True, slots=True)
class Pointing04Image:
    """One image of the archive and its labels (degrees, as in the file name)."""

    path: Path
    subject: int
    series: int
    index: int
    tilt_deg: int
    pan_deg: int

    @property
    def yaw_deg(self) -> int:
        """roadgaze's yaw: > 0 turned to the subject's own left, the archive's pan negated."""
        return -self.pan_deg if self.pan_deg else 0

    @property
    def relative_path(self) -> str:
        """Where the image goes in the evaluation set, relative to its folder."""
        name = f"person{self.subject:02d}{self.series}{self.index:02d}"
        return f"images/Person{self.subject:02d}/{name}{self.tilt_deg:+d}{self.pan_deg:+d}.jpg"


def parse_name(path: Path) -> Pointing04Image | None:
    """The labels in an image's file name; None for a file that is not a Pointing'04 image."""
    match = NAME_PATTERN.match(path.name)
    if match is None:
        return None
    return Pointing04Image(
        path=path,
        subject=int(match["subject"]),
        series=int(match["series"]),
        index=int(match["index"]),
        tilt_deg=int(match["tilt"]),
        pan_deg=int(match["pan"]),
    )


def parse_subjects(text: str) -> frozenset[int]:
    """`1-10` or `1,3,5` (or both mixed) as subject numbers, each within `SUBJECTS`.

    Raises `ConfigError` (one line) for anything else; a range is checked before it is expanded.
    """
    numbers: set[int] = set()
    for part in text.split(","):
        low_text, dash, high_text = part.strip().partition("-")
        try:
            low = int(low_text)
            high = int(high_text) if dash else low
        except ValueError:
            raise ConfigError(f"--subjects: expected e.g. 1-10 or 1,3,5, found {text!r}") from None
        if low > high or low < SUBJECTS.start or high >= SUBJECTS.stop:
            raise ConfigError(
                f"--subjects {part.strip()}: Pointing'04's subjects are "
                f"{SUBJECTS.start}-{SUBJECTS.stop - 1}; give e.g. 1-10 or 1,3,5"
            )
        numbers.update(range(low, high + 1))
    return frozenset(numbers)


def check_folders(source: Path, out_dir: Path) -> None:
    """Raise `DatasetError` when the output folder is the source folder, lies inside it or
    holds it: writing the set would overwrite the archive it reads, or mix with it. Compared by
    resolved path and by device and inode (a bind mount, a second name of one folder)."""
    source_real, out_real = source.resolve(), out_dir.resolve()
    source_id, out_id = _folder_id(source_real), _folder_id(out_real)
    if source_id is None:  # no such folder: find_images says so
        return
    if out_real == source_real or (out_id is not None and out_id == source_id):
        relation = "is"
    elif out_real.is_relative_to(source_real) or source_id in map(_folder_id, out_real.parents):
        relation = "lies inside"
    elif source_real.is_relative_to(out_real) or (
        out_id is not None and out_id in map(_folder_id, source_real.parents)
    ):
        relation = "holds"
    else:
        return
    raise DatasetError(
        f"OUT {out_dir} {relation} the source folder {source}: the evaluation set would "
        "overwrite or mix with the archive; pick an OUT folder outside it"
    )


def _folder_id(path: Path) -> tuple[int, int] | None:
    try:
        status = path.stat()
    except OSError:
        return None
    return status.st_dev, status.st_ino


def find_images(source: Path, subjects: Iterable[int] | None = None) -> list[Pointing04Image]:
    """Every Pointing'04 image under `source` (any depth), in subject, series, index order.

    Only regular files inside `source` are read: symbolic links (to files or folders) and other
    special files are never followed, only counted and logged in one warning. Raises
    `DatasetError` when `source` is not a folder, holds no such image, or holds one image twice
    (two copies of the archive side by side).
    """
    if not source.is_dir():
        raise DatasetError(f"{source}: not a folder; pass the unpacked Pointing'04 archive")
    root = source.resolve()
    wanted = None if subjects is None else set(subjects)
    found: dict[tuple[int, int, int], Pointing04Image] = {}
    skipped: list[Path] = []
    for folder, folders, files in os.walk(root, followlinks=False):
        here = Path(folder)
        below = source / here.relative_to(root)
        skipped.extend(below / name for name in folders if (here / name).is_symlink())
        for name in files:
            image = parse_name(below / name)
            if image is None:
                continue
            if not stat.S_ISREG((here / name).lstat().st_mode):  # a link or a special file
                skipped.append(image.path)
                continue
            if wanted is not None and image.subject not in wanted:
                continue
            key = (image.subject, image.series, image.index)
            if key in found:
                first, second = sorted((found[key].path, image.path))
                raise DatasetError(f"{second} and {first} are the same image; keep one copy")
            found[key] = image
    if skipped:
        log.warning(
            "skipped %d symbolic links or special files under %s (never followed: only regular "
            "files inside the source folder are read), e.g. %s",
            len(skipped),
            source,
            sorted(skipped)[0],
        )
    if not found:
        raise DatasetError(
            f"{source}: no Pointing'04 image (personne<PP><S><II><tilt><pan>.jpg) found"
            + ("" if wanted is None else f" of subjects {sorted(wanted)}")
        )
    return [found[key] for key in sorted(found)]


def build_evaluation_set(
    images: Iterable[Pointing04Image], out_dir: Path, symlink: bool = False
) -> Path:
    """Copy (or symlink) `images` into `out_dir/images/PersonPP/` and write
    `out_dir/ground_truth.csv`; returns the CSV's path.

    Raises `DatasetError` when `out_dir` already holds a `ground_truth.csv`, or is, holds or
    lies in the folder of an image (`check_folders`), before anything is written.
    """
    images = list(images)
    csv_path = out_dir / "ground_truth.csv"
    if csv_path.exists():
        raise DatasetError(f"{csv_path} exists; pick an empty OUT folder or remove it")
    for folder in sorted({image.path.parent for image in images}):
        check_folders(folder, out_dir)
    rows = []
    for image in images:
        target = out_dir / image.relative_path
        target.parent.mkdir(parents=True, exist_ok=True)
        target.unlink(missing_ok=True)
        if symlink:
            target.symlink_to(image.path.resolve())
        else:
            _copy_regular(image.path, target)
        rows.append(
            (
                image.relative_path,
                image.yaw_deg,
                image.tilt_deg,
                image.pan_deg,
                image.tilt_deg,
                image.subject,
                image.series,
            )
        )
    partial = csv_path.with_name(csv_path.name + ".part")
    with partial.open("w", newline="", encoding="utf-8") as stream:
        writer = csv.writer(stream, lineterminator="\n")
        writer.writerow(COLUMNS)
        writer.writerows(rows)
    partial.replace(csv_path)
    return csv_path


def _copy_regular(path: Path, target: Path) -> None:
    """Copy the regular file `path` (opened without following a link) to a new `target`."""
    try:
        descriptor = os.open(path, os.O_RDONLY | os.O_NOFOLLOW)
    except OSError as exc:
        raise DatasetError(
            f"{path}: cannot read it ({exc.strerror}); links are not followed"
        ) from None
    with os.fdopen(descriptor, "rb") as stream:
        if not stat.S_ISREG(os.fstat(descriptor).st_mode):
            raise DatasetError(f"{path}: not a regular file; it is not copied")
        with target.open("xb") as out:
            shutil.copyfileobj(stream, out)


DATA_ENV = "ROADGAZE_DATA"
"""The environment variable naming the folder that holds the evaluation sets (`pointing04-dev`,
`videos`): `roadgaze eval` without a folder, the tests and the figures script look there."""

SET_NAME = "pointing04-dev"
"""The evaluation set's folder name under `$ROADGAZE_DATA`."""


def default_dataset() -> Path | None:
    """`$ROADGAZE_DATA/pointing04-dev` when the variable is set, else None."""
    root = os.environ.get(DATA_ENV, "").strip()
    return Path(root) / SET_NAME if root else None
