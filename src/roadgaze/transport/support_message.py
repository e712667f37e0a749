"""The support message: forward and lane support for the vehicle's forward-collision warning and
lane keeping, one per frame (pure: no Zenoh import).

Each channel is `normal` or `heightened`, with the rule it is at that level by, the rule's
source, why and since when (source timeline). Built from the frame record's monitor outputs
(roadgaze.monitor.behaviours.support); the state message carries the same levels.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from roadgaze.monitor.behaviours.support import HEIGHTENED, support_output
from roadgaze.monitor.protocols.support import FORWARD, LANE
from roadgaze.transport.message_base import Message
from roadgaze.types import FrameRecord, Verdict

__all__ = ["SUPPORT_SCHEMA", "SupportLevel", "SupportMessage"]

SUPPORT_SCHEMA = "roadgaze.support/1"


class SupportLevel(Message):
    """One support channel at one frame."""

    level: Literal["normal", "heightened"] = Field(
        default="heightened",
        description="heightened: the driver is not watching the road, was not watching it "
        "long enough, is impaired, or the service cannot tell (fail-safe).",
    )
    rule: str = Field(
        default="",
        description="The rule it is at this level by, e.g. 'euroncap.support.forward' ('' "
        "when the service has no verdict yet).",
    )
    source: str = Field(default="", description="Where that rule comes from.")
    reason: str = Field(
        default="no verdict yet", description="Why, e.g. 'head in left_mirror', 'no face'."
    )
    since_s: float | None = Field(
        default=None, description="When it took this level (source timeline); null: unknown."
    )

    @classmethod
    def of(cls, verdict: Verdict | None, channel: str) -> SupportLevel:
        """The channel on `verdict`; heightened without one (fail-safe)."""
        output = None if verdict is None else support_output(verdict, channel)
        if output is None:
            return cls()
        level: Literal["normal", "heightened"] = (
            "heightened" if output.value == HEIGHTENED else "normal"
        )
        return cls(
            level=level,
            rule=output.rule,
            source=output.source,
            reason=output.reason,
            since_s=output.since_s,
        )


class SupportMessage(Message):
    """One frame's forward and lane support (docs/zenoh.md, "Support").

    `forward` asks the forward-collision warning (and emergency braking) to act earlier,
    `lane` the lane keeping; a consumer that hears nothing for longer than it can wait takes
    both as heightened (the link or the service is down).
    """

    schema_id: Literal["roadgaze.support/1"] = Field(default="roadgaze.support/1", alias="schema")
    vehicle_id: str
    seq: int = Field(ge=0, description="Per-key sequence number, from 0 at start.")
    t_s: float = Field(description="Source timeline of the frame.")
    wall_time: float = Field(description="Unix time (s) when the message was built.")
    frame: int = Field(ge=0)
    forward: SupportLevel
    lane: SupportLevel

    @classmethod
    def from_record(
        cls, record: FrameRecord, vehicle_id: str, seq: int, wall_time: float
    ) -> SupportMessage:
        """The support message of one frame record."""
        return cls(
            vehicle_id=vehicle_id,
            seq=seq,
            t_s=record.sample.t_s,
            wall_time=wall_time,
            frame=record.sample.frame,
            forward=SupportLevel.of(record.verdict, FORWARD),
            lane=SupportLevel.of(record.verdict, LANE),
        )
