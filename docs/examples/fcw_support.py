"""How a forward-collision warning moves its warning time on roadgaze's forward support.

    python fcw_support.py car-42 tcp/127.0.0.1:7447 [SECONDS]

An FCW warns when the time to collision (TTC) with the vehicle ahead falls below its warning
time. This one warns at TTC 2.1 s while roadgaze says forward support is `normal`, and earlier,
at TTC 3.0 s, while it is `heightened`: the driver is not watching the road (a mirror or the
cluster too), was back on it less than 2 s ago, is drowsy (then to the end of the trip), or
roadgaze cannot tell. Both times are this sketch's, not a standard's: take your FCW's own.

Fail-safe: roadgaze publishes one support message per frame (`vehicle/<id>/dms/support`); one
not heard for 0.5 s means the link or the service is down, and the FCW warns early. Payloads
are untrusted: one too big, not JSON, not the schema or of another vehicle is refused (and
counted); the last good message keeps ageing. One line per change of the warning time.
"""

import json
import sys
import threading
import time
from typing import Any

from roadgaze.config import ZenohConfig
from roadgaze.errors import TransportError
from roadgaze.transport import Keys, SupportMessage, open_session, plan_session
from roadgaze.transport.payloads import PayloadError, parse_json_object

NORMAL_TTC_S, HEIGHTENED_TTC_S = 2.1, 3.0
"""The FCW's warning time (s of TTC) on normal and on heightened forward support."""
STALE_S = 0.5
"""A support message older than this is no support: warn early (roadgaze sends one per frame)."""


def warning_ttc_s(message: SupportMessage | None, age_s: float) -> tuple[float, str]:
    """The FCW's warning time for the last support message heard `age_s` ago, and why."""
    if message is None:
        return HEIGHTENED_TTC_S, "no support message yet"
    if age_s > STALE_S:
        return HEIGHTENED_TTC_S, f"no support message for {age_s:.1f} s: link or service down"
    forward = message.forward
    why = f"{forward.rule}: {forward.reason}"
    if forward.level == "heightened":
        return HEIGHTENED_TTC_S, f"{why}, since {forward.since_s or 0.0:.2f} s"
    return NORMAL_TTC_S, why


class LastSupport:
    """The newest valid support message of one vehicle and when it came (monotonic time)."""

    def __init__(self, vehicle_id: str) -> None:
        self.vehicle_id = vehicle_id
        self.message: SupportMessage | None = None
        self.heard_s = time.monotonic()
        self.refused = 0
        self._lock = threading.Lock()

    def on_sample(self, sample: Any) -> None:
        try:
            message = SupportMessage.model_validate(parse_json_object(sample.payload.to_bytes()))
            if message.vehicle_id != self.vehicle_id:
                raise PayloadError(f"vehicle {message.vehicle_id!r}")
        except (PayloadError, ValueError) as exc:
            with self._lock:
                self.refused += 1
            print(f"refused a support message: {str(exc).splitlines()[0]}", file=sys.stderr)
            return
        with self._lock:
            self.message, self.heard_s = message, time.monotonic()

    def now(self) -> tuple[SupportMessage | None, float]:
        with self._lock:
            return self.message, time.monotonic() - self.heard_s


def main(vehicle_id: str, target: str, seconds: float = float("inf")) -> None:
    config = ZenohConfig(vehicle_id=vehicle_id, connect=[target])
    keys = Keys.from_config(config)
    try:
        session = open_session(plan_session(config, "consumer"), wait_s=min(seconds, 30.0))
    except TransportError as exc:
        print(exc, file=sys.stderr)
        return
    last = LastSupport(vehicle_id)
    shown = None
    deadline = time.monotonic() + seconds
    try:
        subscriber = session.declare_subscriber(keys.support, last.on_sample)
        while time.monotonic() < deadline:
            ttc_s, why = warning_ttc_s(*last.now())
            if ttc_s != shown:
                print(f"FCW warns at TTC {ttc_s:.1f} s ({why})", flush=True)
                shown = ttc_s
            time.sleep(0.05)
        subscriber.undeclare()
    except KeyboardInterrupt:
        pass
    finally:
        session.close()
    print(json.dumps({"refused": last.refused}), file=sys.stderr)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], *(float(arg) for arg in sys.argv[3:4]))
