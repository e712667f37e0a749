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
import os
import re
import shutil
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from roadgaze.errors import DatasetError

NAME_PATTERN = re.compile(
    r"^person(?:ne)?(?P<subject>\d{2})(?P<series>[12])(?P<index>\d{2})"
    r"(?P<tilt>[+-]\d{1,2})(?P<pan>[+-]\d{1,2})\.jpe?g$",
    re.IGNORECASE,
)
"""A Pointing'04 image name; the groups are the subject, series, index, tilt and pan."""

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


def find_images(source: Path, subjects: Iterable[int] | None = None) -> list[Pointing04Image]:
    """Every Pointing'04 image under `source` (any depth), in subject, series, index order.

    Raises `DatasetError` when `source` is not a folder, holds no such image, or holds one image
    twice (two copies of the archive side by side).
    """
    if not source.is_dir():
        raise DatasetError(f"{source}: not a folder; pass the unpacked Pointing'04 archive")
    wanted = None if subjects is None else set(subjects)
    found: dict[tuple[int, int, int], Pointing04Image] = {}
    for path in sorted(source.rglob("*")):
        image = parse_name(path) if path.is_file() else None
        if image is None or (wanted is not None and image.subject not in wanted):
            continue
        key = (image.subject, image.series, image.index)
        if key in found:
            raise DatasetError(f"{path} and {found[key].path} are the same image; keep one copy")
        found[key] = image
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

    Raises `DatasetError` when `out_dir` already holds a `ground_truth.csv`.
    """
    csv_path = out_dir / "ground_truth.csv"
    if csv_path.exists():
        raise DatasetError(f"{csv_path} exists; pick an empty OUT folder or remove it")
    rows = []
    for image in images:
        target = out_dir / image.relative_path
        target.parent.mkdir(parents=True, exist_ok=True)
        target.unlink(missing_ok=True)
        if symlink:
            target.symlink_to(image.path.resolve())
        else:
            shutil.copyfile(image.path, target)
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


DATA_ENV = "ROADGAZE_DATA"
"""The environment variable naming the folder that holds the evaluation sets (`pointing04-dev`,
`videos`): `roadgaze eval` without a folder, the tests and the figures script look there."""

SET_NAME = "pointing04-dev"
"""The evaluation set's folder name under `$ROADGAZE_DATA`."""


def default_dataset() -> Path | None:
    """`$ROADGAZE_DATA/pointing04-dev` when the variable is set, else None."""
    root = os.environ.get(DATA_ENV, "").strip()
    return Path(root) / SET_NAME if root else None
