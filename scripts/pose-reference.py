"""MediaPipe 0.10.14's own pose graph on images: the reference roadgaze's LiteRT pose engine is
held to (tests/landmarks/test_pose.py).

Run by an interpreter with `mediapipe==0.10.14` installed (its legacy solution graph
`pose_landmark_cpu`, static images, the full landmark model, no smoothing, no segmentation,
MediaPipe's default confidences):

    python scripts/pose-reference.py IMAGES.npz OUT.json

IMAGES.npz holds RGB uint8 arrays by name; OUT.json gets, per name, the 33 normalised landmarks
(x, y, z, visibility, presence), the detection (box, 4 keypoints) and the regions the graph made
from the detection and from the landmarks (centre x, y, width, height, rotation), or nulls when
no body was found. The script imports no roadgaze and no OpenCV (the same reference environment
as scripts/hands-reference.py).
"""

from __future__ import annotations

import json
import sys
import types
from pathlib import Path
from typing import Any

import numpy as np

for _name in ("cv2", "matplotlib", "matplotlib.pyplot"):  # imported by drawing helpers only
    sys.modules.setdefault(_name, types.ModuleType(_name))

from mediapipe.python.solution_base import SolutionBase  # noqa: E402

GRAPH = "mediapipe/modules/pose_landmark/pose_landmark_cpu.binarypb"


def _rect(rect: Any) -> list[float] | None:
    if rect is None:
        return None
    return [rect.x_center, rect.y_center, rect.width, rect.height, rect.rotation]


def main(images_path: str, out_path: str) -> None:
    graph = SolutionBase(
        binary_graph_path=GRAPH,
        side_inputs={
            "model_complexity": 1,
            "smooth_landmarks": False,
            "enable_segmentation": False,
            "smooth_segmentation": False,
            "use_prev_landmarks": False,
        },
        calculator_params={
            "posedetectioncpu__TensorsToDetectionsCalculator.min_score_thresh": 0.5,
            "poselandmarkbyroicpu__tensorstoposelandmarksandsegmentation"
            "__ThresholdingCalculator.threshold": 0.5,
        },
        outputs=[
            "pose_landmarks",
            "pose_detection",
            "pose_rect_from_detection",
            "pose_rect_from_landmarks",
        ],
    )
    result = {}
    with np.load(images_path) as images:
        for name in images.files:
            found = graph.process({"image": np.ascontiguousarray(images[name])})
            marks = found.pose_landmarks
            detection = found.pose_detection
            entry: dict[str, Any] = {
                "landmarks": None
                if marks is None
                else [[m.x, m.y, m.z, m.visibility, m.presence] for m in marks.landmark],
                "detection": None,
                "roi_detection": _rect(found.pose_rect_from_detection),
                "roi_landmarks": _rect(found.pose_rect_from_landmarks),
            }
            if detection is not None:
                box = detection.location_data.relative_bounding_box
                entry["detection"] = {
                    "box": [box.xmin, box.ymin, box.width, box.height],
                    "keypoints": [[p.x, p.y] for p in detection.location_data.relative_keypoints],
                    "score": list(detection.score),
                }
            result[name] = entry
    graph.close()
    Path(out_path).write_text(json.dumps(result), encoding="utf-8")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
