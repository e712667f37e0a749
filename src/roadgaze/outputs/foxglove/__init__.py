"""The Foxglove outputs: MCAP recordings (one file or rotating segments) and the live view.

They need the optional extra `roadgaze[foxglove]` (foxglove-sdk, mcap); this package itself
imports neither, so `require_foxglove` can say so in one line before anything starts. The
modules: `channels` (the topics and the messages of one frame), `recorder` (the pipeline sink,
its writer and image threads), `targets` (one MCAP file, the rotating segments), `live` (the
WebSocket server), `recover` (a segment cut short made whole), `layout` (the shipped layout).
"""

from __future__ import annotations

from roadgaze.errors import ConfigError

FOXGLOVE_EXTRA = "pip install 'roadgaze[foxglove]'"


def require_foxglove(what: str) -> None:
    """Raise `ConfigError` (one line naming the extra) unless foxglove-sdk and mcap import."""
    try:
        import foxglove  # noqa: F401  (only asked whether they are there)
        import mcap  # noqa: F401
    except ImportError:
        raise ConfigError(
            f"{what} needs the Foxglove SDK and the MCAP reader, which are not installed: "
            f"{FOXGLOVE_EXTRA}"
        ) from None


__all__ = ["FOXGLOVE_EXTRA", "require_foxglove"]
