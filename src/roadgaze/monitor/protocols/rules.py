"""A protocol rule as data: what it is, its configuration key, units and source. Pure.

Kept so `roadgaze.monitor.protocols.rules` stays importable: the classes live in
`roadgaze.monitor.events`, beside the events that carry them.
"""

from roadgaze.monitor.events import Rule, Trigger

__all__ = ["Rule", "Trigger"]
