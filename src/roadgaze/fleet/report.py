"""`report.html`: the fleet summary for people; one static file, plots embedded as PNG.

Fleet totals first, then the drives that failed and why, the table per driver, three plots and
the table per drive (worst first: most alerts per hour). Every value read from the input (ids,
paths, error messages) is escaped. The page fits a 1280 px wide window: the tables leave out the
alert kinds no drive of the batch raised (said under the table), column heads wrap, and a table
still wider than the page scrolls inside its own box instead of being cut off; plot legends sit
beside the plot, never over a bar.
"""

from __future__ import annotations

import base64
import io
from collections.abc import Callable, Sequence
from datetime import UTC, datetime
from html import escape
from typing import Any

from roadgaze import __version__
from roadgaze.fleet.results import ALERT_KINDS, DriveResult
from roadgaze.fleet.summary import BatchOutcome, GroupStats, by_driver, group_stats, per_hour

MAX_DRIVE_ROWS = 2000
"""Per-drive rows shown in the report (every drive is in summary.parquet)."""

_STYLE = """
body{font:14px/1.4 system-ui,sans-serif;margin:2em auto;max-width:1240px;color:#222;padding:0 1em}
h1{font-size:1.6em}h2{font-size:1.2em;margin-top:2em;border-bottom:1px solid #ccc}
.wide{overflow-x:auto;max-width:100%}
table{border-collapse:collapse;font-size:13px}td,th{padding:3px 6px;border-bottom:1px solid #eee}
th{text-align:left;background:#f4f4f4;position:sticky;top:0;vertical-align:bottom;
white-space:normal;min-width:3.5em}td.n{text-align:right;white-space:nowrap}
.cards{display:flex;flex-wrap:wrap;gap:12px}.card{border:1px solid #ddd;border-radius:6px;
padding:8px 14px;min-width:130px}.card b{display:block;font-size:1.5em}.bad{color:#b00}
td:first-child{white-space:nowrap}img{max-width:100%;margin:8px 0}.note{color:#666}
"""


def _number(value: float | int | None, digits: int = 1, suffix: str = "") -> str:
    if value is None:
        return "-"
    if isinstance(value, int):
        return f"{value:,}{suffix}"
    return f"{value:,.{digits}f}{suffix}"


def _percent(value: float | None) -> str:
    return "-" if value is None else f"{100.0 * value:.1f}%"


def _hours(hours: float) -> str:
    return f"{hours:,.2f} h" if hours >= 1.0 else f"{hours * 60.0:.1f} min"


def _kind_title(kind: str) -> str:
    return kind.replace("_", " ")


def _table(header: Sequence[str], rows: Sequence[Sequence[str]], numeric_from: int = 1) -> str:
    head = "".join(f"<th>{escape(h)}</th>" for h in header)
    body = "".join(
        "<tr>"
        + "".join(
            f'<td class="n">{cell}</td>' if i >= numeric_from else f"<td>{cell}</td>"
            for i, cell in enumerate(row)
        )
        + "</tr>"
        for row in rows
    )
    table = f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"
    return f'<div class="wide">{table}</div>'


def _png(draw: Callable[[Any], None], size: tuple[float, float] = (7.0, 3.2)) -> str:
    """An <img> with what `draw(axes)` plots, as an embedded PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(figsize=size, dpi=100)
    try:
        draw(axes)
        figure.tight_layout()
        buffer = io.BytesIO()
        figure.savefig(buffer, format="png")
    finally:
        plt.close(figure)
    data = base64.b64encode(buffer.getvalue()).decode("ascii")
    return f'<img alt="plot" src="data:image/png;base64,{data}">'


def alerts_by_driver(axes: Any, shown: Sequence[GroupStats]) -> None:
    """Stacked bars of each driver's alerts per hour by kind; the legend beside the bars."""
    left = [0.0] * len(shown)
    for kind in ALERT_KINDS:
        values = [d.alerts_per_h[kind] or 0.0 for d in shown]
        axes.barh([d.name for d in shown], values, left=left, label=_kind_title(kind))
        left = [a + b for a, b in zip(left, values, strict=True)]
    axes.invert_yaxis()
    axes.set_xlabel("alerts per hour of video")
    axes.set_title("Alerts per hour by driver")
    axes.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))


def _plots(ok: Sequence[DriveResult], drivers: Sequence[GroupStats]) -> str:
    if not ok:
        return '<p class="note">No drive finished, so nothing to plot.</p>'
    shown = sorted(drivers, key=lambda d: -sum(v or 0.0 for v in d.alerts_per_h.values()))[:30]
    shown = [d for d in shown if d.drives_ok]

    def off_road(axes: Any) -> None:
        ratios = [100.0 * r.off_road_ratio for r in ok if r.off_road_ratio is not None]
        axes.hist(ratios, bins=20, range=(0, 100), color="#c76")
        axes.set_xlabel("off-road share of the drive (%)")
        axes.set_ylabel("drives")
        axes.yaxis.get_major_locator().set_params(integer=True)
        axes.set_title("Off-road ratio per drive")

    def longest(axes: Any) -> None:
        axes.hist([r.longest_off_road_s for r in ok], bins=20, color="#67a")
        for threshold, label in ((3.0, "3 s"), (6.0, "6 s")):
            axes.axvline(threshold, color="#b00", linestyle="--", linewidth=1)
            axes.text(threshold, axes.get_ylim()[1] * 0.9, f" {label}", color="#b00")
        axes.set_xlabel("longest continuous off-road episode (s)")
        axes.set_ylabel("drives")
        axes.yaxis.get_major_locator().set_params(integer=True)
        axes.set_title("Longest off-road episode per drive")

    if any(rate for d in shown for rate in d.alerts_per_h.values()):
        height = max(2.5, 0.28 * len(shown) + 1.2)
        bars = _png(lambda axes: alerts_by_driver(axes, shown), (9.0, height))
    else:
        bars = '<p class="note">No drive raised an alert, so there are no alert rates to plot.</p>'
    return bars + _png(off_road) + _png(longest)


def _totals(fleet: GroupStats, outcome: BatchOutcome) -> str:
    cards = [
        ("drives", f"{fleet.drives_ok:,} ok of {fleet.drives:,}"),
        ("failed", f"{fleet.drives_failed:,}"),
        ("video", _hours(fleet.hours)),
        ("frames", f"{fleet.frames:,}"),
        ("face found", _percent(fleet.face_found_rate)),
        ("off road", _percent(fleet.off_road_ratio)),
        *(
            (f"{_kind_title(kind)} /h", _number(fleet.alerts_per_h[kind], 2))
            for kind in ALERT_KINDS
        ),
        ("longest off road", _number(fleet.longest_off_road_s, 1, " s")),
        ("loop speed per worker", _number(fleet.processing_fps, 0, " frames/s")),
    ]
    html = "".join(
        f'<div class="card">{escape(label)}<b>{escape(value)}</b></div>' for label, value in cards
    )
    alerts = ", ".join(f"{fleet.alerts[k]:,} {_kind_title(k)}" for k in ALERT_KINDS)
    run = (
        f"This run: {len(outcome.processed):,} drives processed, "
        f"{outcome.count('ok', resumed=True):,} kept from an earlier run, "
        f"{outcome.frames_processed:,} frames in {outcome.wall_s:,.1f} s "
        f"({outcome.frames_per_s:,.1f} frames/s) on the "
        f"{escape(outcome.engine)} engine with {outcome.workers} worker"
        f"{'' if outcome.workers == 1 else 's'}."
    )
    if outcome.interrupted:
        run += ' <b class="bad">The run was stopped before its end; run it again to continue.</b>'
    return (
        f'<div class="cards">{html}</div><p>Alerts: {alerts} ({fleet.critical_alerts:,} reached '
        f"critical).</p><p>{run}</p>"
    )


def _failed(results: Sequence[DriveResult]) -> str:
    unfinished = [r for r in results if r.status != "ok"]
    if not unfinished:
        return "<p>None: every drive finished.</p>"
    rows = [
        [escape(r.drive_id), escape(r.status), escape(r.path), escape(r.error or "")]
        for r in unfinished
    ]
    return _table(["drive", "status", "video", "why"], rows, numeric_from=99)


def _kinds_note(kinds: Sequence[str]) -> str:
    left_out = [_kind_title(k) for k in ALERT_KINDS if k not in kinds]
    if not left_out:
        return ""
    return f'<p class="note">No drive raised {", ".join(left_out)}: those columns are left out.</p>'


def _drivers(drivers: Sequence[GroupStats], kinds: Sequence[str]) -> str:
    header = [
        "driver",
        "drives",
        "failed",
        "video",
        "face found",
        "off road",
        *(f"{_kind_title(kind)} /h" for kind in kinds),
        "longest off road (s)",
        "neutral yaw (deg)",
        "processing fps",
    ]
    rows = [
        [
            escape(d.name),
            _number(d.drives),
            _number(d.drives_failed),
            _hours(d.hours),
            _percent(d.face_found_rate),
            _percent(d.off_road_ratio),
            *(_number(d.alerts_per_h[kind], 2) for kind in kinds),
            _number(d.longest_off_road_s),
            _number(d.neutral_yaw_deg),
            _number(d.processing_fps, 0),
        ]
        for d in drivers
    ]
    return _table(header, rows) + _kinds_note(kinds)


def _drives(ok: Sequence[DriveResult], kinds: Sequence[str]) -> str:
    def badness(result: DriveResult) -> tuple[float, float]:
        alerts = sum(n for _, n in result.alert_counts)
        return (-(per_hour(alerts, result.duration_s) or 0.0), -(result.off_road_ratio or 0.0))

    ordered = sorted(ok, key=badness)
    header = [
        "drive",
        "driver",
        "vehicle",
        "start",
        "duration (s)",
        "face found",
        "off road",
        *(f"{_kind_title(kind)} /h" for kind in kinds),
        "longest off road (s)",
        "neutral yaw (deg)",
        "processing fps",
    ]
    rows = []
    for r in ordered[:MAX_DRIVE_ROWS]:
        counts = dict(r.alert_counts)
        rows.append(
            [
                escape(r.drive_id) + (" *" if r.resumed else ""),
                escape(r.driver_id or ""),
                escape(r.vehicle_id or ""),
                escape(r.start_time or ""),
                _number(r.duration_s),
                _percent(r.face_found_rate),
                _percent(r.off_road_ratio),
                *(_number(per_hour(counts.get(k, 0), r.duration_s), 1) for k in kinds),
                _number(r.longest_off_road_s),
                _number(r.neutral_yaw_deg),
                _number(r.processing_fps, 0),
            ]
        )
    more = len(ordered) - MAX_DRIVE_ROWS
    note = f'<p class="note">{more:,} more drives in summary.parquet.</p>' if more > 0 else ""
    legend = '<p class="note">* kept from an earlier run. Worst first (alerts per hour).</p>'
    return legend + _table(header, rows, numeric_from=4) + _kinds_note(kinds) + note


def render_report(outcome: BatchOutcome, title: str = "roadgaze fleet report") -> str:
    """The whole HTML page for one batch outcome."""
    results = outcome.results
    ok = [r for r in results if r.status == "ok"]
    fleet = group_stats("fleet", results)
    drivers = by_driver(results)
    kinds = [kind for kind in ALERT_KINDS if fleet.alerts[kind]]
    made = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    return (
        f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>{escape(title)}'
        f"</title><style>{_STYLE}</style></head><body><h1>{escape(title)}</h1>"
        f'<p class="note">roadgaze {__version__}, written {made}. Rates are per hour of video; '
        "a long distraction that escalates to critical counts once. Figures per drive: "
        "summary.parquet; per frame: frames/; per alert: alerts/.</p>"
        f"<h2>Fleet</h2>{_totals(fleet, outcome)}"
        f"<h2>Drives that did not finish</h2>{_failed(results)}"
        f"<h2>Drivers</h2>{_drivers(drivers, kinds)}"
        f"<h2>Plots</h2>{_plots(ok, drivers)}"
        f"<h2>Drives</h2>{_drives(ok, kinds)}</body></html>\n"
    )
