"""The deterministic figures the README and docs state, each with the command that prints it.

`scripts/measure-readme.py --check` runs every command below and compares what it prints with
what the documents say; `--update` writes the printed values into the documents (keeping their
line breaks); `--check --cheap` runs only the quick ones (`tests/test_documented_figures.py` does
that on every CI run). Timing figures (the demo's wall time, bench) are not here: they move with
the machine's load, so they are stated with their run in the Measured block instead.

A `Place` is a piece of a document with `{fields}` where the figures go, e.g.
`Place("README.md", "Center-CE MAE {r0_mae:.1f} / {r1_mae:.1f} deg")`. Whitespace in a template
matches any run of whitespace (a figure may sit across a wrapped line); each field matches one
number in the document, and the check compares the number written with the command's value
formatted by the field's format spec.
"""

from __future__ import annotations

import csv
import json
import os
import re
import string
import subprocess
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("ROADGAZE_DATA") or REPO.parent / "shared" / "data")
POINTING04 = DATA / "pointing04-dev"
NUMBER = r"[-+]?\d[\d,]*(?:\.\d+)?"


@dataclass(frozen=True)
class Place:
    """Where a document states figures: `path` (from the repository root) and the text around
    them, with `{name:spec}` for each figure."""

    path: str
    template: str

    def fields(self) -> list[tuple[str, str]]:
        return [
            (name, spec or "")
            for _, name, spec, _ in string.Formatter().parse(self.template)
            if name is not None
        ]

    def pattern(self) -> re.Pattern[str]:
        parts: list[str] = []
        index = 0
        for literal, name, _, _ in string.Formatter().parse(self.template):
            for piece in re.split(r"(\s+)", literal):
                if piece:
                    parts.append(r"\s+" if piece.isspace() else re.escape(piece))
            if name is not None:
                parts.append(f"(?P<f{index}>{NUMBER})")
                index += 1
        if self.template.startswith("|"):  # a table row: the whole line, not a longer row
            parts.insert(0, r"^[ \t]*")
        if self.template.endswith("|"):
            parts.append(r"[ \t]*$")
        return re.compile("".join(parts), re.MULTILINE)


@dataclass(frozen=True)
class Figure:
    """A command (the arguments of `roadgaze`, `{work}` for a scratch folder) and the places
    that state what it prints; `read(stdout, work)` gives the values by field name."""

    name: str
    args: tuple[str, ...]
    read: Callable[[str, Path], dict[str, Any]]
    places: tuple[Place, ...]
    cheap: bool = False
    needs: Path | None = None
    """A folder the command needs (the evaluation data); skipped, and said so, without it."""

    def command(self) -> str:
        return "roadgaze " + " ".join(self.args)


@dataclass(frozen=True)
class Mismatch:
    place: Place
    documented: str
    printed: str

    def __str__(self) -> str:
        return f"{self.place.path}: documents {self.documented}, the command prints {self.printed}"


def compare(place: Place, values: dict[str, Any], text: str) -> tuple[list[Mismatch], str]:
    """The mismatches of `place` in `text`, and `text` with the printed values written in."""
    match = place.pattern().search(text)
    if match is None:
        expected = place.template.format(**values)
        return [Mismatch(place, "nothing like it", repr(expected[:120]))], text
    mismatches = []
    updated = text
    spans = []
    for index, (name, spec) in enumerate(place.fields()):
        printed = format(values[name], spec)
        documented = match.group(f"f{index}")
        if documented != printed:
            mismatches.append(Mismatch(place, f"{name} = {documented}", printed))
            spans.append((match.span(f"f{index}"), printed))
    for (start, end), printed in sorted(spans, reverse=True):
        updated = updated[:start] + printed + updated[end:]
    return mismatches, updated


def run_roadgaze(args: Sequence[str]) -> str:
    """stdout of `python -m roadgaze ARGS` with this interpreter; its stderr passes through."""
    result = subprocess.run(
        [sys.executable, "-m", "roadgaze", *args], stdout=subprocess.PIPE, text=True, check=False
    )
    if result.returncode != 0:
        raise RuntimeError(f"roadgaze {' '.join(args)} failed (exit {result.returncode})")
    return result.stdout


def check_figures(
    figures: Sequence[Figure],
    work: Path,
    update: bool = False,
    run: Callable[[Sequence[str]], str] = run_roadgaze,
    say: Callable[[str], None] = lambda text: print(text, file=sys.stderr),
) -> list[Mismatch]:
    """Run each figure's command and compare (or, with `update`, rewrite) its places."""
    problems: list[Mismatch] = []
    for figure in figures:
        if figure.needs is not None and not figure.needs.is_dir():
            say(f"skipped {figure.name}: {figure.needs} not found (set ROADGAZE_DATA)")
            continue
        args = [arg.replace("{work}", str(work)) for arg in figure.args]
        say(f"$ roadgaze {' '.join(args)}")
        values = figure.read(run(args), work)
        for place in figure.places:
            path = REPO / place.path
            text = path.read_text(encoding="utf-8")
            mismatches, updated = compare(place, values, text)
            problems += mismatches
            if update and updated != text:
                path.write_text(updated, encoding="utf-8")
    return problems


# --- the figures ---------------------------------------------------------------------------------

PAPER_MODELS = ("cylindrical", "ellipsoidal", "ce", "center_ce", "boundary_ce")


def read_paper_tables(stdout: str, work: Path) -> dict[str, Any]:
    values: dict[str, Any] = {}
    table = ""
    for line in stdout.splitlines():
        if line.startswith("Table "):
            table = line.split()[1].rstrip(",")
        cells = line.split()
        if cells and cells[0] in PAPER_MODELS:
            numbers = [cell for cell in cells[1:] if cell != "/"]
            for index, (rmse, largest) in enumerate(zip(numbers[::2], numbers[1::2], strict=True)):
                values[f"{cells[0]}_{table}_{index}_rmse"] = rmse
                values[f"{cells[0]}_{table}_{index}_max"] = largest
    return values


def paper_row(model: str) -> str:
    cells = [
        f"{{{model}_{table}_{index}_rmse}} / {{{model}_{table}_{index}_max}}"
        for table in ("III", "IV")
        for index in range(3)
    ]
    return f"| {model} | " + " | ".join(cells) + " |"


SYNTH_ROW = re.compile(
    r"^\s*(\d+-\d+)\s+(\d+)\s+(\d+)\s+([\d.]+)\s+([-+][\d.]+)\s+([-+][\d.]+)\s+([\d.]+)\s+\|"
    r"\s+([\d.]+)\s+([-+][\d.]+)\s*$",
    re.MULTILINE,
)
SYNTH_COLUMNS = ("frames", "found", "mae", "bias", "offset", "max", "mesh_mae", "mesh_bias")


def read_synth_measure(stdout: str, work: Path) -> dict[str, Any]:
    """The rows of `synth --measure`: r0..r4 (0-15 ... 45-60, then 0-60), as printed, and the
    MAE also as a number (`rN_mae_deg`) for places that round it."""
    values: dict[str, Any] = {}
    for index, row in enumerate(SYNTH_ROW.findall(stdout)):
        for column, cell in zip(SYNTH_COLUMNS, row[1:], strict=True):
            values[f"r{index}_{column}"] = cell
        values[f"r{index}_mae_deg"] = float(row[3])
    return values


SYNTH_RANGES = ((0.0, 15.0), (15.0, 30.0), (30.0, 45.0), (45.0, 60.0))


def read_synth_measure_by_sign(stdout: str, work: Path) -> dict[str, Any]:
    """`read_synth_measure`, plus from its `--csv {work}/synth.csv` the mean error per range and
    sign of the yaw, of the landmarker (`sN_lm_pos`, `sN_lm_neg`) and of the mesh (`sN_mesh_*`),
    and how many frames gave no estimate (`rN_missing`)."""
    values = read_synth_measure(stdout, work)
    with (work / "synth.csv").open(newline="") as stream:
        rows = list(csv.DictReader(stream))
    for index, (low, high) in enumerate(SYNTH_RANGES):
        last = index == len(SYNTH_RANGES) - 1
        for sign, name in ((1.0, "pos"), (-1.0, "neg")):
            errors: dict[str, list[float]] = {"lm": [], "mesh": []}
            for row in rows:
                truth = float(row["truth_yaw_deg"])
                inside = low <= abs(truth) < high or (last and abs(truth) == high)
                if not inside or truth * sign <= 0:
                    continue
                if row["error_deg"]:
                    errors["lm"].append(float(row["error_deg"]))
                if row["mesh_estimate_yaw_deg"]:
                    errors["mesh"].append(float(row["mesh_estimate_yaw_deg"]) - truth)
            for kind, found in errors.items():
                values[f"s{index}_{kind}_{name}"] = f"{sum(found) / len(found):+.2f}"
        values[f"r{index}_missing"] = int(values[f"r{index}_frames"]) - int(
            values[f"r{index}_found"]
        )
    return values


def sign_table_row(index: int, label: str) -> str:
    cells = " | ".join(f"{{s{index}_{k}}}" for k in ("lm_pos", "lm_neg", "mesh_pos", "mesh_neg"))
    return f"| {label} | {cells} |"


def synth_table_row(index: int, label: str) -> str:
    return f"| {label} | " + " | ".join(f"{{r{index}_{c}}}" for c in SYNTH_COLUMNS) + " |"


CLIP_LINE = re.compile(
    r"^\s*(yaw|pitch)\s+raw\s+([\d.]+) \| online\s+([\d.]+) \(([\d.]+) x raw, leaves the raw "
    r"range by ([\d.]+)\) \| offline\s+([\d.]+) \(([\d.]+) x raw, ([\d.]+)\)",
    re.MULTILINE,
)


def read_measure_clip(stdout: str, work: Path) -> dict[str, Any]:
    """`synth --measure-clip ... --noise N`: the clean lines (`yaw_*`, `pitch_*`), then the
    noisy ones (`noisy_yaw_*`, `noisy_pitch_*`)."""
    values: dict[str, Any] = {}
    for index, row in enumerate(CLIP_LINE.findall(stdout)):
        prefix = ("" if index < 2 else "noisy_") + row[0]
        names = ("raw", "online", "online_ratio", "online_out", "offline", "offline_ratio")
        for name, cell in zip((*names, "offline_out"), row[1:], strict=True):
            values[f"{prefix}_{name}"] = cell
    return values


def clip_row(label: str, prefix: str, bold_online: bool) -> str:
    online = f"{{{prefix}_online}} ({{{prefix}_online_ratio}})"
    offline = f"{{{prefix}_offline}} ({{{prefix}_offline_ratio}})"
    online, offline = (f"**{online}**", offline) if bold_online else (online, f"**{offline}**")
    return (
        f"| {label} | {{{prefix}_raw}} | {online}, {{{prefix}_online_out}} | {offline}, "
        f"{{{prefix}_offline_out}} |"
    )


def read_eyes(stdout: str, work: Path) -> dict[str, Any]:
    alls = re.findall(r"^\| all \| (\d+) \| \| ([\d.]+) \| ([\d.]+) \|$", stdout, re.MULTILINE)
    closures = re.search(r"Closure recall .*: (\d+)/(\d+); false closures .*: (\d+)/(\d+)", stdout)
    if len(alls) < 2 or closures is None:
        raise RuntimeError("synth --measure --eyes printed no eye tables")
    return {
        "eye_yaw": alls[0][2],
        "eye_pitch": alls[1][2],
        "closed": closures.group(1),
        "closures": closures.group(2),
        "false_closed": closures.group(3),
        "open": closures.group(4),
    }


EVAL_METHODS = {
    "cylindrical": "Cylindrical",
    "ellipsoidal": "Ellipsoidal",
    "ce": "CE",
    "center_ce": "Center-CE",
    "boundary_ce": "Boundary-CE",
    "service": "**Service yaw** (Center-CE, full range)",
    "mediapipe": "MediaPipe's own matrix yaw (peer)",
}


def read_eval(stdout: str, work: Path) -> dict[str, Any]:
    report = json.loads((work / "eval.json").read_text())
    values: dict[str, Any] = {}
    for method in EVAL_METHODS:
        stats = report["ranges"]["abs_yaw_le_60"][method]
        values[f"{method}_mae"] = stats["mae_deg"]
        values[f"{method}_rmse"] = stats["rmse_deg"]
        values[f"{method}_median"] = stats["median_abs_error_deg"]
        values[f"{method}_found"] = 100 * stats["detection_rate"]
    values["all_service"] = report["ranges"]["all"]["service"]["mae_deg"]
    values["all_center_ce"] = report["ranges"]["all"]["center_ce"]["mae_deg"]
    bins = {int(b["center_deg"]): b["methods"] for b in report["bins"]}
    for center in (-90, 90, -75, 75):
        gain = bins[center]["service"]["mae_deg"] - bins[center]["center_ce"]["mae_deg"]
        values[f"bin_{'m' if center < 0 else 'p'}{abs(center)}"] = gain
    pitch = report["pitch"]
    values["spearman"] = pitch["methods"]["service"]["spearman"]
    lap = pitch["lap"][0]
    values["lap_pct"] = 100 * lap["lap_as_lap"] / lap["n_lap"]
    values["level_lap_pct"] = 100 * lap["level_as_lap"] / lap["n_level"]
    eyes = report["eyes"]
    values.update(
        faces=f"{eyes['faces']:,}",
        open_pct=100 * eyes["open_rate"],
        eyes_closed=eyes["closed"],
        not_judged=eyes["not_judged"],
        gaze=eyes["gaze_yaw_mae_deg"],
        head=eyes["head_yaw_mae_deg"],
    )
    for index, held in enumerate(eyes["held_out"]):
        values[f"held{index}_gaze"] = held["gaze_mae_deg"]
        values[f"held{index}_head"] = held["head_mae_deg"]
    return values


def eval_row(method: str) -> str:
    bold = "**" if method == "service" else ""
    return (
        f"| {EVAL_METHODS[method]} | {bold}{{{method}_mae:.2f}}{bold} | {{{method}_rmse:.2f}} | "
        f"{{{method}_median:.2f}} | {{{method}_found:.1f}}% |"
    )


FIGURES: tuple[Figure, ...] = (
    Figure(
        "the paper's Tables III and IV",
        ("paper-tables",),
        read_paper_tables,
        tuple(Place("docs/paper.md", paper_row(model)) for model in PAPER_MODELS),
        cheap=True,
    ),
    Figure(
        "Center-CE on synthetic stills",
        ("synth", "--measure", "--set", "geometry.model=center_ce", "--csv", "{work}/synth.csv"),
        read_synth_measure_by_sign,
        (
            Place(
                "README.md",
                "Center-CE MAE {r0_mae_deg:.1f} / {r1_mae_deg:.1f} / {r2_mae_deg:.1f} / "
                "{r3_mae_deg:.1f} deg for |yaw| in 0-15",
            ),
            *(
                Place("docs/synth.md", synth_table_row(index, label))
                for index, label in enumerate(("0-15", "15-30", "30-45", "45-60", "0-60"))
            ),
            *(
                Place("docs/synth.md", sign_table_row(index, label))
                for index, label in enumerate(("0-15", "15-30", "30-45", "45-60"))
            ),
        ),
        cheap=True,
    ),
    Figure(
        "Center-CE on synthetic stills at 640x480",
        (
            "synth",
            "--measure",
            "--set",
            "geometry.model=center_ce",
            "--size",
            "640x480",
            "--csv",
            "{work}/synth.csv",
        ),
        read_synth_measure_by_sign,
        (
            Place(
                "docs/synth.md",
                "At 640x480 the MAE is {r0_mae} / {r1_mae} / {r2_mae} / {r3_mae} deg for the four "
                "ranges ({r4_mae} overall). In the 45-60 deg range, {r3_missing} of {r3_frames} "
                "frames give no estimate",
            ),
        ),
    ),
    Figure(
        "the service's yaw on synthetic stills",
        ("synth", "--measure"),
        read_synth_measure,
        (
            Place(
                "README.md",
                "service yaw (full range) MAE {r0_mae_deg:.1f} / {r1_mae_deg:.1f} / "
                "{r2_mae_deg:.1f} / {r3_mae_deg:.1f} deg for \\|yaw\\| in 0-15 / 15-30 / 30-45 / "
                "45-60 (all: {r4_mae_deg:.1f})",
            ),
        ),
    ),
    Figure(
        "the smoothers on the demo drive",
        ("synth", "--measure-clip", "--timeline", "demo", "--size", "640x480", "--noise", "3"),
        read_measure_clip,
        (
            Place(
                "README.md",
                "error is at most the raw error: {yaw_online} against {yaw_raw} deg for yaw, "
                "{pitch_online} against {pitch_raw} for pitch.",
            ),
            Place(
                "README.md",
                "the offline RTS pass gives {noisy_yaw_offline_ratio} x raw for yaw and "
                "{noisy_pitch_offline_ratio} x raw for pitch.",
            ),
            Place("docs/pose.md", clip_row("demo drive, yaw", "yaw", True)),
            Place("docs/pose.md", clip_row("demo drive, pitch", "pitch", True)),
            Place("docs/pose.md", clip_row("demo + noise 3 deg, yaw", "noisy_yaw", False)),
            Place("docs/pose.md", clip_row("demo + noise 3 deg, pitch", "noisy_pitch", False)),
        ),
    ),
    Figure(
        "the smoothers on the yaw/pitch drive",
        ("synth", "--measure-clip", "--timeline", "pose", "--size", "640x480", "--noise", "3"),
        read_measure_clip,
        (
            Place(
                "docs/pose.md",
                clip_row("yaw/pitch drive (`--timeline pose`), yaw", "yaw", False).replace(
                    "**", ""
                ),
            ),
            Place("docs/pose.md", clip_row("same, pitch", "pitch", False).replace("**", "")),
            Place("docs/pose.md", clip_row("same + noise 3 deg, yaw", "noisy_yaw", False)),
            Place("docs/pose.md", clip_row("same + noise 3 deg, pitch", "noisy_pitch", False)),
        ),
    ),
    Figure(
        "the eyes on rendered stills",
        ("synth", "--measure", "--eyes"),
        read_eyes,
        (
            Place(
                "README.md",
                "eye yaw MAE {eye_yaw} deg and eye pitch {eye_pitch} deg after removing the "
                "photo's own offset; closures called closed {closed} of {closures}",
            ),
            Place("README.md", "open eyes called closed {false_closed} of {open}."),
        ),
    ),
    Figure(
        "accuracy on Pointing'04 subjects 1-10",
        (
            "eval",
            str(POINTING04),
            "--workers",
            "2",
            "--report",
            "{work}/eval.json",
            "--no-progress",
        ),
        read_eval,
        (
            *(Place("README.md", eval_row(method)) for method in EVAL_METHODS),
            Place(
                "README.md",
                "the service's yaw has an MAE of {all_service:.2f} deg against Center-CE's "
                "{all_center_ce:.2f}. Per bin: {bin_m90:.1f} / {bin_p90:.1f} deg at -90 / +90, "
                "and {bin_m75:.1f} / {bin_p75:.1f} at -75 / +75",
            ),
            Place("README.md", "a Spearman correlation of {spearman:.3f}."),
            Place(
                "README.md",
                "The `lap` zone takes {lap_pct:.1f} % of the stills looking down 60 deg (|yaw| "
                "<= 15) and {level_lap_pct:.1f} % of the level ones",
            ),
            Place(
                "README.md",
                "On the same {faces} faces found with |yaw| <= 60, the eyes are called open on "
                "{open_pct:.2f} % ({eyes_closed} closed, {not_judged} not judged;",
            ),
            Place(
                "README.md",
                "has an MAE of {gaze:.2f} deg against the head's {head:.2f}. With the deadband",
            ),
            Place(
                "README.md",
                "the other half gives {held0_gaze:.2f} against {held0_head:.2f} and "
                "{held1_gaze:.2f} against {held1_head:.2f}",
            ),
        ),
        needs=POINTING04,
    ),
)
"""Every deterministic figure of the README and the docs that a command reproduces."""
