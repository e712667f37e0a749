"""Where the yaw models used to live; kept so `roadgaze.geometry.YAW_MODELS` stays importable.

The models are in `roadgaze.pose.geometry`; this module re-exports its public names.
"""

from roadgaze.pose.geometry import *  # noqa: F403
from roadgaze.pose.geometry import __all__  # noqa: F401
