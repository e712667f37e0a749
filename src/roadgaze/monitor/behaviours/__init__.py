"""The monitor's behaviours: one module each, a state slice and a pure step over the context."""

from roadgaze.monitor.behaviours.clearing import DISTRACTION_KINDS, Clearing
from roadgaze.monitor.behaviours.degraded import Degraded, DegradedState
from roadgaze.monitor.behaviours.distraction import Distraction, DistractionState
from roadgaze.monitor.behaviours.drowsy import Drowsy, DrowsyState
from roadgaze.monitor.behaviours.eye_closure import CLOSURE_ALERTS, EyeClosure, EyeClosureState
from roadgaze.monitor.behaviours.non_functional import NonFunctional, NonFunctionalState
from roadgaze.monitor.behaviours.phone_use import PhoneUse, PhoneUseState
from roadgaze.monitor.behaviours.support import Support, SupportState
from roadgaze.monitor.behaviours.temporary_failure import FailureState, TemporaryFailure
from roadgaze.monitor.behaviours.unavailable import Unavailable, UnavailableState
from roadgaze.monitor.behaviours.unresponsive import Unresponsive, UnresponsiveState
from roadgaze.monitor.behaviours.vats import Vats, VatsState

__all__ = [
    "CLOSURE_ALERTS",
    "DISTRACTION_KINDS",
    "Clearing",
    "Degraded",
    "DegradedState",
    "Distraction",
    "DistractionState",
    "Drowsy",
    "DrowsyState",
    "EyeClosure",
    "EyeClosureState",
    "FailureState",
    "NonFunctional",
    "NonFunctionalState",
    "PhoneUse",
    "PhoneUseState",
    "Support",
    "SupportState",
    "TemporaryFailure",
    "Unavailable",
    "UnavailableState",
    "Unresponsive",
    "UnresponsiveState",
    "Vats",
    "VatsState",
]
