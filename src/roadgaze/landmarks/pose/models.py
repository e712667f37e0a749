"""The body models: MediaPipe's pose detector and its full pose landmark model (BlazePose).

`pose_detection.tflite` and `pose_landmark_full.tflite`, each with its size and SHA-256 as
MediaPipe's build pins them (`third_party/external_files.bzl`), on Google's model storage (those
URLs) and in the PyPI wheel `mediapipe==0.10.14` under `mediapipe/modules/pose_*/`. The wheel
has no lite or heavy landmark model (MediaPipe 0.10.14 downloads those at run time), so the
full one is the only variant with a second source. They are provisioned with the hand models
(`roadgaze.landmarks.hands.models`: the same cache, sources, checks and `roadgaze model fetch
hands`).
"""

from __future__ import annotations

from collections.abc import Mapping

from roadgaze.landmarks.hands.model_file import HandModelFile
from roadgaze.landmarks.model_store import ExpectedFile

DETECTOR_NAME = "pose_detection.tflite"
LANDMARKS_NAME = "pose_landmark_full.tflite"

POSE_MODEL_FILES: Mapping[str, HandModelFile] = {
    model.name: model
    for model in (
        HandModelFile(
            DETECTOR_NAME,
            ExpectedFile(
                2_959_046, "9ba9dd3d42efaaba86b4ff0122b06f29c4122e756b329d89dca1e297fd8f866c"
            ),
            "1678737489600422",
            "mediapipe/modules/pose_detection/pose_detection.tflite",
        ),
        HandModelFile(
            LANDMARKS_NAME,
            ExpectedFile(
                6_440_512, "e9a5c5cb17f736fafd4c2ec1da3b3d331d6edbe8a0d32395855aeb2cdfd64b9f"
            ),
            "1661875894245786",
            "mediapipe/modules/pose_landmark/pose_landmark_full.tflite",
        ),
    )
}
"""The body model files by name (sizes from the wheel, SHA-256 from MediaPipe's build file)."""
