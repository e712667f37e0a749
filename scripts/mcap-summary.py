#!/usr/bin/env python3
"""What an MCAP recording holds, read with the `mcap` Python reader (roadgaze[foxglove]).

    .venv/bin/python scripts/mcap-summary.py FILE.mcap [FILE.mcap ...]

Per file: the message count and span, the chunks, every channel with its schema, encodings and
message count, the `roadgaze` metadata (time base and offset, source, version) and the alerts.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from mcap.reader import make_reader


def summarise(path: str) -> None:
    with Path(path).open("rb") as handle:
        reader = make_reader(handle)
        summary = reader.get_summary()
        if summary is None or summary.statistics is None:
            print(f"{path}: no summary (cut short? `roadgaze recover {path}`)")
            return
        stats = summary.statistics
        span_s = (stats.message_end_time - stats.message_start_time) / 1e9
        print(
            f"{path}: {stats.message_count} messages over {span_s:.2f} s in "
            f"{len(summary.chunk_indexes)} chunks"
        )
        for channel in sorted(summary.channels.values(), key=lambda c: c.topic):
            schema = summary.schemas.get(channel.schema_id)
            name, encoding = (schema.name, schema.encoding) if schema else ("-", "-")
            count = stats.channel_message_counts.get(channel.id, 0)
            print(
                f"  {channel.topic:24s} {name:27s} {encoding:10s} {channel.message_encoding:9s}"
                f" {count:6d}"
            )
        for record in reader.iter_metadata():
            if record.name == "roadgaze":
                print(f"  metadata roadgaze: {json.dumps(dict(record.metadata), sort_keys=True)}")
        for _, _, message in reader.iter_messages(topics=["/roadgaze/alerts"]):
            alert = json.loads(message.data)
            reason = f" ({alert['reason']})" if alert.get("reason") else ""
            print(f"  alert at t={alert['t_s']:.3f} s: {alert['kind']} {alert['level']}{reason}")


if __name__ == "__main__":
    for argument in sys.argv[1:] or [sys.exit(__doc__)]:
        summarise(argument)
