"""MediaPipe 0.10.14's own hand graph on images: the reference roadgaze's LiteRT hand engine is
held to (tests/landmarks/test_hands.py).

Run by an interpreter with `mediapipe==0.10.14` installed (its legacy solution graph
`hand_landmark_tracking_cpu`, static images, the full models, two hands, MediaPipe's defaults):

    python scripts/hands-reference.py IMAGES.npz OUT.json

IMAGES.npz holds RGB uint8 arrays by name; OUT.json gets, per name, the hands' 21 normalised
landmarks, the handedness model's own score (the legacy graph's `Left`) and the palm
detections' keypoints.
The script imports no roadgaze and no OpenCV (the reference environment needs only mediapipe,
numpy < 2, protobuf < 5, absl-py, attrs and flatbuffers).
"""

from __future__ import annotations

import json
import sys
import types
from pathlib import Path

import numpy as np

for _name in ("cv2", "matplotlib", "matplotlib.pyplot"):  # imported by drawing helpers only
    sys.modules.setdefault(_name, types.ModuleType(_name))

from mediapipe.python.solution_base import SolutionBase  # noqa: E402

GRAPH = "mediapipe/modules/hand_landmark/hand_landmark_tracking_cpu.binarypb"


def main(images_path: str, out_path: str) -> None:
    graph = SolutionBase(
        binary_graph_path=GRAPH,
        side_inputs={"model_complexity": 1, "num_hands": 2, "use_prev_landmarks": False},
        calculator_params={
            "palmdetectioncpu__TensorsToDetectionsCalculator.min_score_thresh": 0.5,
            "handlandmarkcpu__ThresholdingCalculator.threshold": 0.5,
        },
        outputs=["multi_hand_landmarks", "multi_handedness", "palm_detections"],
    )
    result = {}
    with np.load(images_path) as images:
        for name in images.files:
            found = graph.process({"image": np.ascontiguousarray(images[name])})
            hands = [
                [[mark.x, mark.y, mark.z] for mark in hand.landmark]
                for hand in found.multi_hand_landmarks or []
            ]
            handedness = []
            for entry in found.multi_handedness or []:
                top = entry.classification[0]
                # Its label map reads the model's score as `Left` (the tasks API as `Right`).
                handedness.append(top.score if top.label == "Left" else 1.0 - top.score)
            palms = [
                [[point.x, point.y] for point in palm.location_data.relative_keypoints]
                for palm in found.palm_detections or []
            ]
            result[name] = {"hands": hands, "handedness": handedness, "palms": palms}
    graph.close()
    Path(out_path).write_text(json.dumps(result), encoding="utf-8")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
