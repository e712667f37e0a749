"""The non-functional notice's settings (in `[monitor]`): when the service tells the driver that
it cannot monitor, how often it says so again, and when the notice ends.

Kept apart from `roadgaze.config.settings`, which builds `[monitor]` on them. The conditions and
each default's source: docs/monitor.md, "Non-functional notices"; the rules:
`roadgaze.monitor.protocols.euroncap`.
"""

from __future__ import annotations

from pydantic import Field

from roadgaze.config.section import Section

NOTICE_LIMIT_S = 10.0
"""Euro NCAP 2026's limit: a non-functional system is told within 10 s of its onset."""
REPEAT_LIMIT_S = 600.0
"""Euro NCAP 2026's limit: the notice is shown permanently or again every 10 minutes."""


class NoticeSettings(Section):
    """The non-functional notice: the eyes or the face hidden while the driver faces the road."""

    non_functional_after_s: float = Field(default=5.0, gt=0, le=NOTICE_LIMIT_S)
    """The eyes (or the face) hidden this long while moving: `non_functional` is raised (Euro
    NCAP 2026: within 10 s; the 5 s are roadgaze's choice, longer than a hand passing in front of
    the face, short enough for the frame rate and the camera's latency to stay inside 10 s)."""
    non_functional_repeat_s: float = Field(default=600.0, gt=0, le=REPEAT_LIMIT_S)
    """A notice still in force is raised again this often (Euro NCAP 2026: permanently or every
    10 minutes; the state message shows it permanently as well)."""
    non_functional_clear_s: float = Field(default=2.0, ge=0)
    """The notice ends once the condition has been gone this long (roadgaze's choice: a single
    frame that shows the eyes behind dark lenses does not end it)."""
