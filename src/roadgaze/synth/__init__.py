"""Synthetic ground truth: one real photo's face mesh turned to known poses and re-rendered."""

from roadgaze.synth.clip import (
    DEFAULT_FPS,
    TRUTH_HEADER,
    read_truth_csv,
    render_clip,
    render_frames,
    truth_path_for,
    write_truth_csv,
)
from roadgaze.synth.measure import (
    YAW_RANGES_DEG,
    YawRecovery,
    format_measurement,
    measure_yaw_recovery,
    write_measurement_csv,
)
from roadgaze.synth.renderer import (
    DEFAULT_SIZE,
    FaceRenderer,
    PhotoMesh,
    default_photo_path,
    load_photo,
    mesh_triangles,
    photo_landmarks_px,
)
from roadgaze.synth.timeline import (
    DEFAULT_TRANSITION_S,
    MAX_ABS_PITCH_DEG,
    MAX_ABS_YAW_DEG,
    MAX_CLIP_S,
    Keyframe,
    Timeline,
    parse_timeline,
)

__all__ = [
    "DEFAULT_FPS",
    "DEFAULT_SIZE",
    "DEFAULT_TRANSITION_S",
    "MAX_ABS_PITCH_DEG",
    "MAX_ABS_YAW_DEG",
    "MAX_CLIP_S",
    "TRUTH_HEADER",
    "YAW_RANGES_DEG",
    "FaceRenderer",
    "Keyframe",
    "PhotoMesh",
    "Timeline",
    "YawRecovery",
    "default_photo_path",
    "format_measurement",
    "load_photo",
    "measure_yaw_recovery",
    "mesh_triangles",
    "parse_timeline",
    "photo_landmarks_px",
    "read_truth_csv",
    "render_clip",
    "render_frames",
    "truth_path_for",
    "write_measurement_csv",
    "write_truth_csv",
]
