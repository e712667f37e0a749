"""The daemon around the loop (`service.daemon`): stop signals, systemd notify, watchdog."""

from roadgaze.service.sdnotify import Notifier, socket_address
from roadgaze.service.signals import STOP_SIGNALS, StopFlag, signal_handlers, sigterm_as_interrupt
from roadgaze.service.supervision import Supervisor, waiting_for_camera

__all__ = [
    "STOP_SIGNALS",
    "Notifier",
    "StopFlag",
    "Supervisor",
    "signal_handlers",
    "sigterm_as_interrupt",
    "socket_address",
    "waiting_for_camera",
]
