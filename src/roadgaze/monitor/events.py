"""What a behaviour hands back at one sample: alerts to raise, alerts whose cause ended, per-frame
outputs; each by the rule it applies. Pure.

A behaviour (`roadgaze.monitor.behaviours`) never builds an `Alert` or a `Verdict` itself: it
returns events and the monitor's fold turns them into the frame's alerts (`Raise`, stamped with
the sample's timers), a `cleared` alert (`Resolve`) and the verdict's `outputs` (`Publish`).
"""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.config import MonitorConfig
from roadgaze.types import AlertKind, AlertLevel, Output

__all__ = ["Event", "Publish", "Raise", "Resolve", "Rule", "Trigger", "published"]


@dataclass(frozen=True, slots=True)
class Rule:
    """One requirement: `key` names it on the bus (e.g. `addw.distraction.above_50kmh`; its first
    part is the protocol), `config_key` is the `[monitor]` field that holds its value, in `unit`;
    `source` says where it comes from and `what` what it asks for. `impairment`: an alert by
    this rule says the driver is impaired (drowsy, asleep: a non-transient state), so forward
    and lane support stay heightened to the end of the trip
    (roadgaze.monitor.behaviours.support)."""

    key: str
    config_key: str
    unit: str
    source: str
    what: str
    impairment: bool = False

    @property
    def protocol(self) -> str:
        """`addw`, `euroncap` or `roadgaze` (roadgaze's own)."""
        return self.key.partition(".")[0]

    def value(self, config: MonitorConfig) -> float | None:
        """The configured value (None for an optional setting that is unset)."""
        value = getattr(config, self.config_key)
        return None if value is None else float(value)

    def limit(self, config: MonitorConfig) -> float:
        """The configured value of a setting that is always set (a time, a level)."""
        value = self.value(config)
        if value is None:
            raise ValueError(f"rule {self.key}: [monitor] {self.config_key} is not set")
        return value


@dataclass(frozen=True, slots=True)
class Trigger:
    """When a distraction warning is due at this speed: after `warn_s` of distraction, by `rule`
    (plus `allowance_s` of it granted for non-nominal conditions)."""

    warn_s: float
    rule: Rule
    allowance_s: float = 0.0


@dataclass(frozen=True, slots=True)
class Raise:
    """Raise an alert of `kind` and `level` by `rule` (for `cleared`: the kinds it `clears`)."""

    kind: AlertKind
    level: AlertLevel
    rule: Rule
    reason: str = ""
    clears: tuple[AlertKind, ...] = ()


@dataclass(frozen=True, slots=True)
class Resolve:
    """The cause of these alerts has ended: clear those of them that are active (the `clearing`
    behaviour raises one `cleared` alert for all of a sample's). `recovery`: a failure that ended
    at this sample; the `cleared` alert lists recoveries after the others."""

    kinds: tuple[AlertKind, ...]
    recovery: bool = False


@dataclass(frozen=True, slots=True)
class Publish:
    """A per-frame output that is not an alert (e.g. a support level for other systems): `name`
    is `value` by `rule`, `since_s` when it took that value. A behaviour publishes it at every
    sample it holds; it lands in `Verdict.outputs` for that frame."""

    name: str
    value: str
    rule: Rule
    reason: str = ""
    since_s: float | None = None

    def output(self) -> Output:
        return Output(
            self.name, self.value, self.rule.key, self.rule.source, self.reason, self.since_s
        )


Event = Raise | Resolve | Publish


def published(events: tuple[Event, ...]) -> tuple[Output, ...]:
    """The per-frame outputs among `events`, as the verdict carries them."""
    return tuple(event.output() for event in events if isinstance(event, Publish))
