"""The messages roadgaze publishes on Zenoh, as pydantic models (pure: no Zenoh import).

Payloads are these models serialised as JSON (`application/json`); each names its schema and
version in the field `schema`. `roadgaze schema` prints their JSON Schemas. Messages are built
from the frame record (`YawMessage.from_record`) and the monitor's alerts
(`AlertMessage.from_alert`).
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field

from roadgaze.transport.message_base import Message as _Message
from roadgaze.transport.support_message import SupportLevel, SupportMessage
from roadgaze.types import (
    Alert,
    AlertKind,
    AlertLevel,
    EyeCalibrationStatus,
    EyeStatus,
    EyesVerdict,
    FrameRecord,
    Gaze,
)

YAW_SCHEMA = "roadgaze.yaw/3"
ALERT_SCHEMA = "roadgaze.alert/4"
STATE_SCHEMA = "roadgaze.state/6"


class EyeFields(_Message):
    """The eyes as the monitor judged them (docs/monitor.md); in the yaw and state messages."""

    eyes: EyeStatus = Field(
        default=EyeStatus.UNAVAILABLE, description="open, closed or unavailable"
    )
    eyes_reason: str = Field(
        default="", description="Why unavailable, or why narrowed lids are open."
    )
    eye_openness: float | None = Field(
        default=None, description="Lid gap / eye width (about 0.3 open, 0.1 closed)."
    )
    gaze_yaw_deg: float | None = Field(
        default=None, description="Head yaw + eye yaw beyond the deadband; > 0 = driver's left."
    )
    gaze_pitch_deg: float | None = Field(default=None, description="> 0 = up.")
    gaze_source: Literal["eyes", "head", "none"] = "none"
    closure_s: float = Field(default=0.0, ge=0, description="Current closure length.")
    perclos: float | None = Field(
        default=None, ge=0, le=1, description="Closed share of the last 60 s (judged time)."
    )
    blinks: int = Field(default=0, ge=0, description="Blinks in the PERCLOS window.")
    eyes_unavailable_s: float = Field(default=0.0, ge=0)
    degraded: bool = Field(
        default=False, description="Eyes unavailable too long: head pose only (impaired)."
    )

    @staticmethod
    def of(eyes: EyesVerdict) -> dict[str, Any]:
        """The fields' values from the monitor's verdict."""
        return {
            "eyes": eyes.status,
            "eyes_reason": eyes.reason,
            "eye_openness": eyes.openness,
            "gaze_yaw_deg": eyes.gaze_yaw_deg,
            "gaze_pitch_deg": eyes.gaze_pitch_deg,
            "gaze_source": eyes.gaze_source,
            "closure_s": max(0.0, eyes.closure_s),
            "perclos": eyes.perclos,
            "blinks": eyes.blinks,
            "eyes_unavailable_s": max(0.0, eyes.unavailable_s),
            "degraded": eyes.degraded,
        }


class YawMessage(EyeFields):
    """One frame's head pose (yaw, pitch, roll), glance zone, eyes and road-ahead decision.

    `roadgaze.yaw/2` extended `/1` with `pitch_deg`, `pitch_raw_deg`, `roll_deg`, `zone`,
    `eyes_on_road` and `neutral_pitch_deg`; `roadgaze.yaw/3` adds the eye fields (`eyes`,
    `eye_openness`, `gaze_*`, `closure_s`, `perclos`, `blinks`, `eyes_unavailable_s`,
    `degraded`), and `eyes_on_road` is false while the eyes are closed. Every earlier field keeps
    its name and meaning. `yaw_deg` and `pitch_deg` are the camera's measurement; with a camera
    not in front (`[monitor] camera_mounting`) `neutral_yaw_deg` / `neutral_pitch_deg` are the
    road-ahead pose as the camera sees it too, so `yaw_deg - neutral_yaw_deg` keeps its meaning
    (the monitor judges in the driver's frame: the state message).
    """

    schema_id: Literal["roadgaze.yaw/3"] = Field(default="roadgaze.yaw/3", alias="schema")
    vehicle_id: str
    seq: int = Field(ge=0, description="Per-key sequence number, from 0 at start.")
    t_s: float = Field(
        description="Source timeline: video time in replay, seconds since start live."
    )
    wall_time: float = Field(description="Unix time (s) when the message was built.")
    frame: int = Field(ge=0)
    face: bool
    yaw_deg: float | None = Field(description="Smoothed yaw, > 0 = head turned to driver's left.")
    yaw_raw_deg: float | None
    yaw_rate_dps: float | None = None
    on_road: bool | None = Field(description="Road ahead; None when no face and not turned away.")
    gaze: Gaze
    neutral_yaw_deg: float
    n_faces: int = Field(default=0, ge=0)
    pitch_deg: float | None = Field(
        default=None, description="Smoothed pitch, > 0 = looking up; null without a face."
    )
    pitch_raw_deg: float | None = None
    roll_deg: float | None = Field(
        default=None,
        description="Eye-line roll, > 0 = counter-clockwise in the image (not validated).",
    )
    zone: str | None = Field(
        default=None,
        description="Glance zone: road, lap, cluster, centre_stack, left_mirror, right_mirror "
        "(or another configured zone), far_left / far_right / roof (ADDW's distraction area 1), "
        "body_lean (the head moved out of the driving place) or away; null when the gaze is "
        "unknown.",
    )
    eyes_on_road: bool | None = Field(
        default=None,
        description="zone == 'road' and the eyes not closed; null when the gaze is unknown.",
    )
    neutral_pitch_deg: float = 0.0

    @classmethod
    def from_record(
        cls, record: FrameRecord, vehicle_id: str, seq: int, wall_time: float
    ) -> YawMessage:
        """The yaw message of one frame record."""
        sample, verdict = record.sample, record.verdict
        neutral = verdict.camera_neutral_deg or (verdict.neutral_yaw_deg, verdict.neutral_pitch_deg)
        return cls(
            vehicle_id=vehicle_id,
            seq=seq,
            t_s=sample.t_s,
            wall_time=wall_time,
            frame=sample.frame,
            face=sample.face,
            yaw_deg=sample.yaw_deg,
            yaw_raw_deg=sample.yaw_raw_deg,
            yaw_rate_dps=sample.yaw_rate_dps,
            on_road=verdict.on_road,
            gaze=verdict.gaze,
            neutral_yaw_deg=neutral[0],
            n_faces=sample.n_faces,
            pitch_deg=sample.pitch_deg,
            pitch_raw_deg=sample.pitch_raw_deg,
            roll_deg=sample.roll_deg,
            zone=verdict.zone,
            eyes_on_road=verdict.eyes_on_road,
            neutral_pitch_deg=neutral[1],
            **EyeFields.of(verdict.eyes),
        )


class AlertMessage(_Message):
    """One monitor event (see docs/monitor.md).

    `roadgaze.alert/2` adds the kinds `microsleep`, `sleep`, `drowsy`, `unresponsive` and
    `degraded`, and the fields `closure_s`, `perclos` and `reason`; `roadgaze.alert/3` adds the
    kinds `temporary_failure` and `permanent_failure` (with the failure in `reason`) and the
    fields `rule` and `source`: the protocol rule the alert fired by and where that rule comes
    from (docs/monitor.md, "Protocols"); `roadgaze.alert/4` adds the kinds `phone_use` (a phone
    in hand while moving) and `non_functional` (the eyes or the face hidden while the camera
    works; the condition in `reason`). Every earlier field keeps its name and meaning.
    """

    schema_id: Literal["roadgaze.alert/4"] = Field(default="roadgaze.alert/4", alias="schema")
    vehicle_id: str
    seq: int = Field(ge=0)
    kind: AlertKind
    level: AlertLevel
    t_s: float
    wall_time: float
    yaw_deg: float | None
    off_road_s: float = Field(ge=0, description="Current continuous off-road time.")
    window_off_road_s: float = Field(ge=0, description="Off-road time in the VATS window.")
    unavailable_s: float = Field(default=0.0, ge=0)
    speed_kmh: float | None = None
    clears: list[AlertKind] = Field(
        default_factory=list, description="For 'cleared': the alerts it ends."
    )
    closure_s: float = Field(default=0.0, ge=0, description="Current eye closure length.")
    perclos: float | None = Field(default=None, ge=0, le=1)
    reason: str = Field(default="", description="Why it fired, in a few words.")
    rule: str = Field(
        default="",
        description="The protocol rule it fired by, e.g. 'addw.distraction.above_50kmh', "
        "'euroncap.long_distraction' ('' for none).",
    )
    source: str = Field(default="", description="Where that rule comes from.")

    @classmethod
    def from_alert(cls, alert: Alert, vehicle_id: str, seq: int, wall_time: float) -> AlertMessage:
        """The wire form of one monitor alert."""
        return cls(
            vehicle_id=vehicle_id,
            seq=seq,
            kind=alert.kind,
            level=alert.level,
            t_s=alert.t_s,
            wall_time=wall_time,
            yaw_deg=alert.yaw_deg,
            off_road_s=max(0.0, alert.off_road_s),
            window_off_road_s=max(0.0, alert.window_off_road_s),
            unavailable_s=max(0.0, alert.unavailable_s),
            speed_kmh=alert.speed_kmh,
            clears=[kind for kind in alert.clears if kind is not AlertKind.CLEARED],
            closure_s=max(0.0, alert.closure_s),
            perclos=alert.perclos,
            reason=alert.reason,
            rule=alert.rule,
            source=alert.source,
        )


class TransportStatus(_Message):
    """The Zenoh link as the daemon sees it (`roadgaze.state/3` adds every field after
    `speed_rejected`)."""

    mode: Literal["peer", "client", "router"]
    session_open: bool
    connected: bool
    """A transport to a router, peer or client is open (Zenoh transport events)."""
    peers: int = 0
    routers: int = 0
    session_reopens: int = 0
    yaw_sent: int = 0
    support_sent: int = Field(default=0, description="roadgaze.state/6: support messages sent.")
    vss_sent: int = Field(default=0, description="COVESA VSS values published.")
    alerts_sent: int = Field(default=0, description="Alerts published while the link was up.")
    not_sent: int = Field(
        default=0,
        description="yaw_not_sent + support and VSS values not sent + alerts_failed.",
    )
    pending_alerts: int = Field(
        default=0, description="Client mode: alerts held by roadgaze until the session opens."
    )
    speed_messages: int = 0
    speed_rejected: int = 0
    clients: int = 0
    link_downs: int = Field(default=0, description="Times the link went down since start.")
    connect: list[str] = Field(default_factory=list, description="Endpoints connected to.")
    listen: list[str] = Field(default_factory=list, description="Endpoints listened on.")
    alerts_published: int = 0
    alerts_held_while_down: int = Field(
        default=0,
        description="Published while no transport was open: in the publisher's cache, "
        "delivered to subscribers with history or recovery once the link is back.",
    )
    alerts_beyond_cache: int = Field(
        default=0,
        description="Held while down and pushed out of the cache: lost to those "
        "who had not received them.",
    )
    alerts_failed: int = 0
    alert_cache_size: int = 0
    yaw_not_sent: int = 0
    speed_oversize: int = Field(default=0, description="Speed payloads dropped unread (size).")
    state_queries_answered: int = 0
    alerts_waiting: int = Field(
        default=0,
        ge=0,
        description="roadgaze.state/4: alerts published while no link was up (or held before "
        "the session opened), or on a link with no subscriber yet, and still waiting for one; "
        "gone if the daemon stops first.",
    )
    alerts_lost: int = Field(
        default=0,
        ge=0,
        description="roadgaze.state/4: alerts that will never reach a subscriber: pushed out "
        "of the cache, put failed, dropped before the session opened, or no link at exit.",
    )
    undelivered_alerts: list[str] = Field(
        default_factory=list,
        description="roadgaze.state/4: the newest waiting and lost alerts (at most 20 of "
        "each), e.g. '#3 long_distraction critical t=5.00s: held, no link yet'.",
    )


class MonitorSnapshot(EyeFields):
    gaze: Gaze
    on_road: bool
    neutral_yaw_deg: float
    yaw_deg: float | None
    zone: str | None = None
    neutral_pitch_deg: float = 0.0
    pitch_deg: float | None = None
    off_road_s: float
    window_off_road_s: float
    unavailable_s: float
    vats_armed: bool
    active_alerts: list[str]
    moving: bool
    speed_kmh: float | None
    speed_source: Literal["none", "waiting", "fresh", "stale", "invalid"]
    alert_counts: dict[str, int]
    protocol: Literal["addw", "euroncap", "both"] = "both"
    camera_mounting: str = Field(
        default="front", description="The camera mounting preset (or 'custom' angles)."
    )
    distraction_s: float = Field(default=0.0, ge=0, description="The long-distraction timer.")
    distraction_warn_s: float | None = Field(
        default=None, description="Distraction time that warns at this speed; null: inactive."
    )
    distraction_rule: str = Field(default="", description="The rule giving it.")
    failure: str = Field(
        default="", description="The temporary failure in force ('' for none), with its reason."
    )
    eye_calibration: EyeCalibrationStatus = Field(
        default=EyeCalibrationStatus.NONE,
        description="none, learning or calibrated: the eyes move the gaze only once the "
        "driver's resting eye direction is learned (calibrated).",
    )
    phone_detection: bool = Field(
        default=False,
        description="roadgaze.state/6: phone detection runs (false: `[hands] enabled` is off or "
        "the hand models are missing, so `phone_use` is never raised).",
    )
    phone_use: bool | None = Field(
        default=None,
        description="roadgaze.state/6: the last frame's phone judgement (null: it cannot judge, "
        "or phone detection is off).",
    )
    non_functional: str = Field(
        default="",
        description="roadgaze.state/6: the non-functional notice in force ('' for none), with "
        "its reason, e.g. 'eyes_hidden: eyes hidden facing the road (eyes hidden) 5.0 s'; "
        "shown in every state message while it lasts (docs/monitor.md).",
    )
    support_forward: SupportLevel = Field(
        default_factory=SupportLevel,
        description="roadgaze.state/6: forward support at the last frame (the support message).",
    )
    support_lane: SupportLevel = Field(
        default_factory=SupportLevel, description="roadgaze.state/6: lane support, likewise."
    )


class StateMessage(_Message):
    """Answer of the `state` queryable: health, monitor state, counters and config summary.

    `roadgaze.state/2` added `zone`, `pitch_deg` and `neutral_pitch_deg` to `monitor`;
    `roadgaze.state/3` adds link and delivery fields to `transport` (see `TransportStatus`, and
    `vss_sent`), the speed source `invalid`, the eye fields of the yaw message to `monitor`, and
    the status `degraded` (with a problem saying why) while the eyes have been unavailable too
    long. `roadgaze.state/4` adds to `monitor` the protocol, the camera mounting, the
    distraction timer and the time and rule that warn at the current speed, and the temporary
    failure in force, and the eye calibration (`eye_calibration`); `permanent_failure` (the
    camera gone past `permanent_failure_s`); and `alerts_waiting`, `alerts_lost` and
    `undelivered_alerts` to `transport` (the alert ledger). `roadgaze.state/5` adds
    `driver_ambiguous`; `roadgaze.state/6` adds `phone_detection`, `phone_use`,
    `non_functional` (the notice in force, for as long as it lasts), `support_forward` and
    `support_lane` (the support message's levels) to `monitor` and `support_sent` to
    `transport`. The monitor's angles are in the driver's frame (the camera mounting applied).
    Every earlier field keeps its name and meaning.
    """

    schema_id: Literal["roadgaze.state/6"] = Field(default="roadgaze.state/6", alias="schema")
    vehicle_id: str
    wall_time: float
    status: Literal["starting", "running", "degraded", "stopping", "stopped"]
    problems: list[str] = Field(default_factory=list, description="Why the status is degraded.")
    t_s: float | None = Field(description="Timestamp of the last sample processed.")
    uptime_s: float
    source: str
    source_status: str
    frames: int
    faces: int
    driver_ambiguous: str = Field(
        default="",
        description="roadgaze.state/5: why the driver cannot be told from another face in view "
        "on the last frame ('' when it can: docs/landmarks.md); also among `problems`.",
    )
    camera_reopens: int = 0
    permanent_failure: str = Field(
        default="", description="The permanent failure in force ('' for none), with its reason."
    )
    transport: TransportStatus
    monitor: MonitorSnapshot
    config: dict[str, Any]


MESSAGE_MODELS: dict[str, type[_Message]] = {
    "yaw": YawMessage,
    "alert": AlertMessage,
    "state": StateMessage,
    "support": SupportMessage,
}


def json_schemas() -> dict[str, dict[str, Any]]:
    """The JSON Schema of every published message, by name."""
    return {
        name: model.model_json_schema(by_alias=True, mode="serialization")
        for name, model in MESSAGE_MODELS.items()
    }
