"""One MediaPipe model file of phone detection: its name, size and SHA-256, where Google serves
it and where the PyPI wheel `mediapipe==0.10.14` has it (the hand and body models' tables)."""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.landmarks.model_store import ExpectedFile

ASSETS_URL = "https://storage.googleapis.com/mediapipe-assets/"


@dataclass(frozen=True, slots=True)
class HandModelFile:
    """One model file: its name, what it must be, where Google serves it, where the wheel has it."""

    name: str
    expected: ExpectedFile
    generation: str
    wheel_member: str

    @property
    def url(self) -> str:
        return f"{ASSETS_URL}{self.name}?generation={self.generation}"
