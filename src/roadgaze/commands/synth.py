"""`roadgaze synth`: a video of a real face turning to known poses, with its truth CSV, and the
measurements against that truth (yaw sweep, pitch grid, a clip through the pose stage)."""

from __future__ import annotations

import argparse
import logging
import re
from dataclasses import replace
from pathlib import Path
from typing import Any

from roadgaze.commands.options import common_options
from roadgaze.config import Config
from roadgaze.errors import ConfigError
from roadgaze.logs import log_written

log = logging.getLogger("roadgaze.synth")

EXAMPLE_TIMELINE = "0:2,40:3.5,0:2,-35:1,0:2"


def parse_size(text: str) -> tuple[int, int]:
    """'640x480' -> (640, 480); raises ConfigError."""
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if match is None:
        raise ConfigError(f"--size expects WIDTHxHEIGHT in pixels, e.g. 320x320, found '{text}'")
    width, height = int(match.group(1)), int(match.group(2))
    if not (64 <= width <= 4096 and 64 <= height <= 4096):
        raise ConfigError(f"--size must be within 64..4096 px per side, found {width}x{height}")
    return width, height


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "synth",
        parents=[common_options()],
        help="render a ground-truth clip of a real face turning to given poses (or measure)",
        description="Render a video of the face in one photo turning to the poses of a timeline "
        "(the photo's MediaPipe face mesh lifted to 3D, nodded and turned about a neck pivot and "
        "re-rendered) and write <stem>.truth.csv beside it (t_s,yaw_deg,pitch_deg). With "
        "--measure, instead sweep yaw over frames and print how well the landmark stage and the "
        "yaw model recover it; --measure --pitch: a yaw x pitch grid of stills, pitch per |pitch| "
        "range and the zones; --measure-clip: render the timeline and print the raw, online and "
        "offline (RTS) yaw and pitch errors, the smoothers' overshoot, pitch per |pitch| range "
        "and the zones against the truth; --measure --eyes: stills with the eyes turned and the "
        "lids closed, the recovered eye direction and openness per bin and the closed/open "
        "classifier against the truth.",
        epilog="Timeline: comma-separated YAW[/PITCH][;FIELD=VALUE...]:SECONDS keyframes in "
        "degrees and seconds; each segment turns to its pose during the first --transition "
        f"seconds (cosine ease) and holds it. Example: {EXAMPLE_TIMELINE}. Yaw > 0: head turned "
        "to the person's own left. Eye fields: eyes=open|closed|half|0..1, eye_yaw=DEG, "
        "eye_pitch=DEG (within +-35; they move over --eye-transition), e.g. "
        "'0:2,0;eyes=closed:1.5,0;eye_yaw=-25;eye_pitch=-30:2'; the truth CSV then also has "
        "eye_yaw_deg,eye_pitch_deg,openness.",
    )
    parser.add_argument(
        "--timeline",
        default=EXAMPLE_TIMELINE,
        metavar="SPEC",
        help=f"keyframes YAW[/PITCH][;FIELD=VALUE...]:SECONDS,... (default {EXAMPLE_TIMELINE}); "
        "'eyes': a drive with a 1.5 s and a 4 s eye closure and an eyes-only glance; with "
        "--measure-clip also 'demo' (the demo's drive) or 'pose' (a yaw/pitch drive, the default)",
    )
    parser.add_argument("--out", type=Path, metavar="VIDEO", help="output .mp4, .avi or .mkv")
    parser.add_argument(
        "--photo", type=Path, help="portrait with one frontal face (default: skimage's astronaut)"
    )
    parser.add_argument("--fps", type=float, default=15.0, help="frames per second (default 15)")
    parser.add_argument(
        "--eye-transition",
        type=float,
        default=0.1,
        metavar="SECONDS",
        help="duration of each eye movement and lid closure between keyframes (default 0.1)",
    )
    parser.add_argument(
        "--size", type=str, default="320x320", metavar="WxH", help="frame size (default 320x320)"
    )
    parser.add_argument(
        "--transition",
        type=float,
        default=0.5,
        metavar="SECONDS",
        help="duration of each turn between keyframes (default 0.5)",
    )
    measure = parser.add_argument_group("measurement")
    measure.add_argument(
        "--measure",
        action="store_true",
        help="sweep yaw over stills, run landmarks + the configured yaw model, print MAE per range",
    )
    measure.add_argument(
        "--step", type=float, default=1.0, metavar="DEG", help="sweep step (default 1 deg)"
    )
    measure.add_argument(
        "--max-yaw", type=float, default=60.0, metavar="DEG", help="sweep -DEG..DEG (default 60)"
    )
    measure.add_argument(
        "--stills",
        action="store_true",
        help="run the landmarker on each still in IMAGE mode (default: VIDEO mode over the sweep)",
    )
    measure.add_argument("--csv", type=Path, metavar="FILE", help="write per-yaw results here")
    measure.add_argument(
        "--eyes",
        action="store_true",
        help="with --measure: stills of rendered eyes (direction, openness, closed/open) at "
        "640x480 unless --size is given; --csv writes one row per still",
    )
    measure.add_argument(
        "--pitch",
        action="store_true",
        help="with --measure: a yaw x pitch grid of stills (yaw step 15, pitch -40..40 step 5): "
        "pitch per |pitch| range for each pitch estimator, and the zones",
    )
    measure.add_argument(
        "--measure-clip",
        action="store_true",
        help="render --timeline, run landmarks and the pose stage over it (VIDEO mode) and print "
        "the smoothers' errors and overshoot, pitch per |pitch| range and the zones",
    )
    measure.add_argument(
        "--noise",
        type=float,
        default=0.0,
        metavar="DEG",
        help="with --measure-clip: also add white noise of DEG to the raw yaw and pitch",
    )
    measure.add_argument(
        "--seeds", type=int, default=5, metavar="N", help="noise seeds (default 5)"
    )
    parser.set_defaults(handler=run)


def clip_timeline(text: str) -> str:
    """The timeline `--measure-clip` renders: 'pose', 'demo' or a spec of its own."""
    if text == "pose":
        from roadgaze.synth import POSE_TIMELINE

        return POSE_TIMELINE
    if text == "demo":
        from roadgaze.demo import DRIVE_TIMELINE

        return DRIVE_TIMELINE
    return text


def run(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.synth import load_photo, parse_timeline, render_clip, truth_path_for

    size = parse_size(args.size)
    if args.measure_clip:
        from roadgaze.synth import format_clip_measurement, measure_clip

        if not 0.0 <= args.noise <= 30.0:
            raise ConfigError(f"--noise must be within 0..30 deg, found {args.noise}")
        if not 1 <= args.seeds <= 100:
            raise ConfigError(f"--seeds must be within 1..100, found {args.seeds}")
        timeline = args.timeline if args.timeline != EXAMPLE_TIMELINE else "pose"
        parsed = parse_timeline(clip_timeline(timeline), args.transition)
        clip = measure_clip(
            parsed,
            config,
            photo=args.photo,
            size=size,
            fps=args.fps,
            noise_deg=args.noise,
            seeds=args.seeds,
        )
        print(format_clip_measurement(replace(clip, timeline=timeline)))
        return 0
    if args.measure and args.eyes:
        from roadgaze.synth import (
            format_eye_measurement,
            measure_eye_recovery,
            write_eye_measurement_csv,
        )

        eye_size = size if args.size != "320x320" else (640, 480)
        eye_result = measure_eye_recovery(config, args.photo, eye_size)
        print(format_eye_measurement(eye_result))
        if args.csv is not None:
            write_eye_measurement_csv(args.csv, eye_result)
            print(f"wrote {args.csv}")
        return 0
    if args.measure and args.pitch:
        from roadgaze.synth import format_pitch_measurement, measure_pitch_recovery

        print(format_pitch_measurement(measure_pitch_recovery(config, args.photo, size)))
        return 0
    if args.measure:
        from roadgaze.synth import format_measurement, measure_yaw_recovery, write_measurement_csv

        if not 0.1 <= args.step <= 30.0:
            raise ConfigError(f"--step must be within 0.1..30 deg, found {args.step}")
        if not 0.0 < args.max_yaw <= 80.0:
            raise ConfigError(f"--max-yaw must be within 0..80 deg, found {args.max_yaw}")
        result = measure_yaw_recovery(
            config,
            photo=args.photo,
            size=size,
            step_deg=args.step,
            max_yaw_deg=args.max_yaw,
            video=not args.stills,
        )
        print(format_measurement(result))
        if args.csv is not None:
            write_measurement_csv(args.csv, result)
            log_written(args.csv)
        return 0
    if args.out is None:
        raise ConfigError("--out VIDEO is required to render a clip (or pass --measure)")
    spec = args.timeline
    if spec == "eyes":
        from roadgaze.synth import EYE_DRIVE_TIMELINE

        spec = EYE_DRIVE_TIMELINE
    timeline = parse_timeline(spec, args.transition, args.eye_transition)
    load_photo(args.photo)  # fail fast on a bad photo before any work
    truth = render_clip(timeline, args.out, photo=args.photo, fps=args.fps, size=size)
    log.info(
        "rendered %d frames, %g s at %g fps, %dx%d",
        len(truth),
        timeline.duration_s,
        args.fps,
        size[0],
        size[1],
    )
    log_written(args.out)
    log_written(truth_path_for(args.out))
    return 0
