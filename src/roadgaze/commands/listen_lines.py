"""The readable lines `roadgaze listen` prints for each checked message (pure formatting)."""

from __future__ import annotations

from typing import Any


def format_pretty(kind: str, vehicle: str, payload: dict[str, Any] | None, raw: str) -> str:
    """One readable line for a received message."""
    if payload is None:
        return f"{kind:<6} {vehicle} undecodable payload: {raw[:120]}"
    if kind == "alive":
        return f"alive  {vehicle} {'joined' if payload.get('alive') else 'left'}"
    if kind == "alert":
        yaw = payload.get("yaw_deg")
        yaw_text = "no face" if yaw is None else f"yaw={yaw:+.1f}°"
        text = (
            f"ALERT  {vehicle} #{payload.get('seq')} {payload.get('kind')} "
            f"{payload.get('level')} t={payload.get('t_s', 0.0):.2f}s "
            f"off_road={payload.get('off_road_s', 0.0):.2f}s "
            f"window={payload.get('window_off_road_s', 0.0):.2f}s {yaw_text}"
        )
        if payload.get("clears"):
            text += " clears=" + ",".join(payload["clears"])
        if payload.get("closure_s"):
            text += f" closure={payload['closure_s']:.2f}s"
        if payload.get("reason"):
            text += f" ({payload['reason']})"
        return text
    if kind == "yaw":
        yaw = payload.get("yaw_deg")
        yaw_text = "    --  " if yaw is None else f"{yaw:+7.1f}°"
        # Fixed widths: the columns stay aligned from #10 and t=10 s on.
        seq, t_text = f"#{payload.get('seq')}", f"t={payload.get('t_s', 0.0):.2f}s"
        line = f"yaw    {vehicle} {seq:<7} {t_text:<10} {yaw_text}"
        if "zone" not in payload:  # roadgaze.yaw/1
            return f"{line} {payload.get('gaze')}"
        pitch = payload.get("pitch_deg")
        pitch_text = "    --  " if pitch is None else f"{pitch:+7.1f}°"
        line = f"{line} pitch {pitch_text} {payload.get('zone') or payload.get('gaze')}"
        if "eyes" not in payload:  # roadgaze.yaw/2
            return line
        return f"{line} {_eyes_text(payload)}"
    if kind == "state":
        transport = payload.get("transport", {})
        # alerts_sent counts only alerts published while a link was up; those published while
        # it was down (held, then recovered from the cache) and those lost are counted apart.
        delivery = f"alerts_sent={transport.get('alerts_sent')}"
        if "alerts_held_while_down" in transport:
            delivery += f" held={transport.get('alerts_held_while_down')}"
        if "alerts_lost" in transport:
            delivery += f" lost={transport.get('alerts_lost')}"
        return (
            f"state  {vehicle} status={payload.get('status')} frames={payload.get('frames')} "
            f"{delivery} problems={payload.get('problems')}"
        )
    return f"{kind:<6} {vehicle} {raw[:200]}"


def _eyes_text(payload: dict[str, Any]) -> str:
    """The eyes of a yaw/3 message in a few words: state, openness, gaze, closure, PERCLOS."""
    eyes = str(payload.get("eyes"))
    openness = payload.get("eye_openness")
    text = f"eyes {eyes}" + ("" if openness is None else f" {openness:.2f}")
    gaze = payload.get("gaze_yaw_deg")
    if gaze is not None and payload.get("gaze_source") == "eyes":
        text += f" gaze {gaze:+.1f}°/{payload.get('gaze_pitch_deg') or 0.0:+.1f}°"
    if payload.get("closure_s"):
        text += f" closed {payload['closure_s']:.1f}s"
    if payload.get("perclos") is not None:
        text += f" perclos {payload['perclos']:.2f}"
    if payload.get("degraded"):
        text += " DEGRADED"
    return text


def format_vss(key: str, value: str) -> str:
    """One readable line for a checked VSS value: `vss    Vehicle/Driver/IsEyesOnRoad = true`."""
    return f"vss    {key} = {value}"
