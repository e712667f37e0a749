"""What `roadgaze listen` tells about the alerts it did not print: now
`roadgaze.transport.alert_book`, shared by every consumer (re-exported here)."""

from __future__ import annotations

from roadgaze.transport.alert_book import AlertBook as AlertBook
from roadgaze.transport.alert_book import seq_range as seq_range
