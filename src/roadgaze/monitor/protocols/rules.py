"""A protocol rule as data: what it is, its configuration key, units and source. Pure."""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.config import MonitorConfig

__all__ = ["Rule", "Trigger"]


@dataclass(frozen=True, slots=True)
class Rule:
    """One requirement: `key` names it on the bus (e.g. `addw.distraction.above_50kmh`),
    `config_key` is the `[monitor]` field that holds its value, in `unit`."""

    key: str
    config_key: str
    unit: str
    source: str
    what: str

    def value(self, config: MonitorConfig) -> float | None:
        """The configured value (None for an optional setting that is unset)."""
        value = getattr(config, self.config_key)
        return None if value is None else float(value)


@dataclass(frozen=True, slots=True)
class Trigger:
    """When a distraction warning is due at this speed: after `warn_s` of distraction, by `rule`
    (plus `allowance_s` of it granted for non-nominal conditions)."""

    warn_s: float
    rule: Rule
    allowance_s: float = 0.0
