"""Every roadgaze alert of one vehicle, once, in order, checked: the input of an FCW.

    python consume_alerts.py car-42 tcp/127.0.0.1:7447           # development: plain TCP
    python consume_alerts.py car-42 consumer-fcw/zenoh.json5       # `roadgaze security init` file

It may start before the router or the daemon (an FCW boots first): it waits for them.
roadgaze's `AlertConsumer` does the work `roadgaze listen` does: the advanced subscriber's
history gives the daemon's last alerts when it joins (and when a daemon appears later), recovery
fetches alerts missed while a link was down, and each alert is checked (size, JSON, schema,
vehicle id, seq continuing its publisher's sequence). Missing numbers come as a range, a plain
put is refused, and when a second process publishes this vehicle's alerts both are handed on,
flagged (on an open bus either may be the forger: never drop a real alert); totals at exit.
"""

import logging
import math
import sys
import time
from pathlib import Path

from roadgaze.config import ZenohConfig
from roadgaze.errors import TransportError
from roadgaze.transport import consumer_events as events
from roadgaze.transport.consumer import AlertConsumer


def config_for(target: str) -> ZenohConfig:
    if target.endswith((".json5", ".json")):
        return ZenohConfig(config_file=Path(target))
    return ZenohConfig(connect=[target])


def act(event: events.ConsumerEvent) -> None:
    """What the FCW does with each event: here, print it."""
    match event:
        case events.AlertReceived():  # a second publisher's too: flagged, never dropped
            alert = event.alert
            flag = f" SUSPICIOUS: {event.suspicious}" if event.suspicious else ""
            print(f"{alert['kind']} {alert['level']} seq={event.seq} t={alert['t_s']:.2f}s{flag}")
        case events.AlertsMissed() | events.AlertRefused() | events.SecondPublisher():
            print(event.describe(), file=sys.stderr)
        case events.MessageRejected() | events.DuplicateAlert():
            print(f"refused an alert: {event}", file=sys.stderr)
        case events.LinkLost():
            print(f"{event.whatami} gone: zenoh reconnects by itself", file=sys.stderr)
    sys.stdout.flush()


def main(vehicle_id: str, target: str, seconds: float = math.inf) -> None:
    logging.basicConfig(level=logging.INFO, format="%(message)s")  # "waiting for a router ..."
    deadline = time.monotonic() + seconds
    try:
        consumer = AlertConsumer.connect(config_for(target), vehicle_id, wait_s=seconds)
    except TransportError as exc:
        print(exc, file=sys.stderr)
        return
    with consumer:
        try:
            for event in consumer.events(deadline - time.monotonic()):
                act(event)
        except KeyboardInterrupt:
            pass
        for event in consumer.finish():
            act(event)
        book = consumer.book
        print(
            f"{book.printed} alerts, {book.flagged} flagged (a second publisher), "
            f"{book.missed} missed, {book.rejected} rejected, {book.foreign - book.flagged} "
            "refused (plain puts)",
            file=sys.stderr,
        )


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], *(float(arg) for arg in sys.argv[3:4]))
