"""The one exception hierarchy of roadgaze.

Every error a user can cause (bad file, missing camera, bad config value, missing model) is a
`RoadgazeError` whose message says what was expected, what was found and what to do. The CLI
prints it as one line and exits with `exit_code`; it never shows a traceback for these.
"""


class RoadgazeError(Exception):
    """Base class: a problem the user can act on, reported as one clear line."""

    exit_code = 2


class ConfigError(RoadgazeError):
    """A configuration file, environment variable or option has a bad value."""


class ModelError(RoadgazeError):
    """The face landmarker model cannot be found, fetched or verified."""


class SourceError(RoadgazeError):
    """A video file, image folder or camera cannot be opened or read."""


class SpeedError(SourceError):
    """A vehicle speed that is not one: a speed track that cannot be read or holds a bad value,
    or a constant speed outside 0-400 km/h (`roadgaze.speed`)."""


class DatasetError(RoadgazeError):
    """An evaluation data set is missing or malformed."""


class TransportError(RoadgazeError):
    """The Zenoh session cannot be configured or opened."""
