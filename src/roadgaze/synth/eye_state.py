"""The truth of both rendered eyes: where they look and how open they are (`EyeRenderer`)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class EyeState:
    """Truth for both eyes: eye-in-head yaw/pitch (degrees, project convention) and openness."""

    eye_yaw_deg: float = 0.0
    eye_pitch_deg: float = 0.0
    openness_right: float = 1.0
    openness_left: float = 1.0

    @classmethod
    def both(
        cls, eye_yaw_deg: float = 0.0, eye_pitch_deg: float = 0.0, openness: float = 1.0
    ) -> EyeState:
        return cls(eye_yaw_deg, eye_pitch_deg, openness, openness)

    @property
    def at_rest(self) -> bool:
        """Open as photographed and looking ahead: the texture needs no edit."""
        return (
            self.eye_yaw_deg == 0.0
            and self.eye_pitch_deg == 0.0
            and self.openness_right >= 1.0
            and self.openness_left >= 1.0
        )
