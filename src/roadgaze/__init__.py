"""roadgaze: real-time driver head-yaw monitoring for forward-collision warning.

Pipeline: capture -> MediaPipe FaceLandmarker -> Center-CE face model -> Kalman smoother
-> inattention monitor -> Eclipse Zenoh. Sign convention everywhere: yaw > 0 means the head is
turned to the driver's own left (ISO 8855); pitch > 0 means looking up.
"""

__version__ = "0.2.0"
