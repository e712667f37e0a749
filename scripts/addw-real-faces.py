"""The ADDW / Euro NCAP acceptance cases on real faces: Pointing'04 stills held in a 15 fps clip.

    PYTHONPATH=src python scripts/addw-real-faces.py [--data ../shared/data/pointing04-dev]
        [--subjects 1-10] [--series 1]

Per subject, each case is its own clip (a fresh pipeline, the default configuration): the frontal
still for 3 s, the look for its time, the frontal still for 3 s, with the vehicle speed given to
the monitor. Cases: a 4 s look to yaw +75 and -75 deg and into the lap (tilt -60, yaw 0) at
70 km/h, which must raise `long_distraction` 1.5-3.6 s after the look starts; a 1.5 s glance to
each mirror (yaw +-45) at 70 km/h and an 8 s lap glance at 10 km/h, which must raise no
distraction alert. Prints one line per case and subject, then a summary; exits 1 on a failure.
"""

from __future__ import annotations

import argparse
import csv
import sys
import tempfile
from pathlib import Path

import cv2

from roadgaze.capture import open_source
from roadgaze.config import Config
from roadgaze.pipeline import Pipeline, create_detector
from roadgaze.types import FrameRecord

FPS = 15.0
ROAD_S = 3.0
DISTRACTION = {"long_distraction", "vats", "unresponsive", "driver_unavailable"}
"""The distraction alerts (roadgaze.monitor.escalation.DISTRACTION_KINDS): a face lost at once
in a turn (MediaPipe finds no face at 75 deg on some subjects) is `driver_unavailable`."""
CASES = (
    # name, (yaw, pitch) of the look, seconds, km/h, expected alert window after the look starts
    ("left 75 at 70 km/h", (75, 0), 4.0, 70.0, (1.5, 3.6)),
    ("right 75 at 70 km/h", (-75, 0), 4.0, 70.0, (1.5, 3.6)),
    ("lap at 70 km/h", (0, -60), 4.0, 70.0, (1.5, 3.6)),
    ("left mirror 1.5 s at 70 km/h", (45, 0), 1.5, 70.0, None),
    ("right mirror 1.5 s at 70 km/h", (-45, 0), 1.5, 70.0, None),
    ("lap 8 s at 10 km/h", (0, -60), 8.0, 10.0, None),
)


def write_clip(path: Path, parts: list[tuple[Path, float]]) -> None:
    first = cv2.imread(str(parts[0][0]))
    height, width = first.shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"FFV1"), FPS, (width, height))
    for image_path, seconds in parts:
        image = cv2.imread(str(image_path))
        for _ in range(round(seconds * FPS)):
            writer.write(image)
    writer.release()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=Path("../shared/data/pointing04-dev"))
    parser.add_argument("--subjects", default="1-10")
    parser.add_argument("--series", type=int, default=1)
    args = parser.parse_args()
    if not (args.data / "ground_truth.csv").is_file():
        print(f"no Pointing'04 data at {args.data}", file=sys.stderr)
        return 2
    low, _, high = args.subjects.partition("-")
    subjects = range(int(low), int(high or low) + 1)
    images: dict[tuple[int, int, int], Path] = {}
    with (args.data / "ground_truth.csv").open() as handle:
        for row in csv.DictReader(handle):
            if int(row["series"]) == args.series:
                key = (int(row["subject"]), int(row["yaw_deg"]), int(row["pitch_deg"]))
                images[key] = args.data / row["file"]
    config = Config()
    failures = 0
    delays: list[float] = []
    with tempfile.TemporaryDirectory() as folder:
        for subject in subjects:
            for name, (yaw, pitch), look_s, kmh, window in CASES:
                front, look = images[(subject, 0, 0)], images[(subject, yaw, pitch)]
                clip = Path(folder) / "clip.mkv"
                write_clip(clip, [(front, ROAD_S), (look, look_s), (front, ROAD_S)])
                records: list[FrameRecord] = []
                with open_source(str(clip), config) as source:
                    detector = create_detector(config)
                    try:
                        pipeline = Pipeline.from_config(config, detector, speed=lambda kmh=kmh: kmh)
                        records = [step.record for step in pipeline.frames(source)]
                    finally:
                        detector.close()
                alerts = [a for r in records for a in r.alerts]
                hits = [a for a in alerts if a.kind.value in DISTRACTION]
                zones = sorted({r.verdict.zone or "-" for r in records
                                if ROAD_S + 0.5 <= r.t_s < ROAD_S + look_s})  # fmt: skip
                if window is None:
                    ok = not hits
                    said = "none" if ok else ", ".join(f"{a.label} {a.t_s:.2f}" for a in hits)
                else:
                    first = hits[0].t_s - ROAD_S if hits else None
                    ok = first is not None and window[0] <= first <= window[1]
                    said = "none" if first is None else f"{hits[0].label} +{first:.2f} s"
                    if first is not None:
                        delays.append(first)
                failures += not ok
                print(f"subject {subject:2d} {name:30s} {'PASS' if ok else 'FAIL'} {said}"
                      f" (zones {', '.join(zones)})", flush=True)  # fmt: skip
    if delays:
        print(f"warning delays: {min(delays):.2f}-{max(delays):.2f} s after the look starts")
    print(f"{failures} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
