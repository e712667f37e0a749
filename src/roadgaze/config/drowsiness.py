"""The drowsiness level's settings (in `[monitor]`): when it warns and what each sign needs.

Kept apart from `roadgaze.config.settings`, which builds `[monitor]` on them. The level, its signs
and each default's source: docs/monitor.md, "Drowsiness"; the rules: `roadgaze.monitor.protocols`.
"""

from __future__ import annotations

from pydantic import Field

from roadgaze.config.section import Section


class DrowsinessSettings(Section):
    """The drowsiness level (a KSS-like scale, 5 with no sign of sleepiness up to 9) and its
    signs, each counted within `perclos_window_s`."""

    drowsiness_warn_level: int = Field(default=7, ge=6, le=9)
    """`drowsy` warns at this level or above (Euro NCAP 2026: KSS 7 or more equivalent)."""
    drowsiness_min_speed_kmh: float = Field(default=50.0, ge=0)
    """Under the `euroncap` protocol the level warns only at this speed or above (Euro NCAP
    2026: impairment at least 50 km/h); an unknown speed warns (fail-safe)."""
    blink_duration_drowsy_s: float = Field(default=0.15, gt=0)
    """A mean blink duration at or above this is a sign (Anund et al. 2017: blinks longer than
    0.15 s with sleepiness); judged over at least three blinks."""
    blink_rate_drowsy_per_min: float | None = Field(default=None, gt=0)
    """Blinks per minute at or above this are a sign; None (default): not a sign, the published
    findings disagree on the direction (docs/monitor.md)."""
    yawn_opening: float = Field(default=0.6, gt=0)
    """The mouth is open for a yawn above this opening (inner lip gap / inner mouth width, from
    the face landmarks' lips): roadgaze's choice between speech's widest syllables and a yawn
    as measured on rendered faces (docs/monitor.md, "Drowsiness")."""
    yawn_min_s: float = Field(default=2.0, gt=0)
    """An opening held this long is a yawn (a yawn lasts about 6 s, Provine 1986; a syllable
    a fraction of a second): roadgaze's choice."""
    yawns_drowsy: int = Field(default=2, ge=1)
    """This many yawns within the window are a sign (roadgaze's choice)."""
    nod_drop_deg: float = Field(default=15.0, gt=0)
    """The head dropping this far below its road pitch with the eyes closed starts a nod."""
    nod_max_s: float = Field(default=2.0, gt=0)
    """A drop that comes back up within this is a nod (longer: a look down, or sleep)."""
    nods_drowsy: int = Field(default=1, ge=1)
    """This many nods within the window are a sign (roadgaze's choice)."""
