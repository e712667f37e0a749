"""The `[record]` configuration section: MCAP recordings and the Foxglove live view (pure).

Part of `Config` (`roadgaze.config.settings`); used by `run --record DIR`, `replay --mcap FILE`,
`run --foxglove [HOST:]PORT` and by the MCAP frame source (docs/foxglove.md).
"""

from __future__ import annotations

from typing import Literal, Self

from pydantic import Field, model_validator

from roadgaze.config.section import Section

MIN_SEGMENTS_ON_DISK = 2
"""`max_disk_mb` must hold at least this many full segments: the open one and one closed."""


class RecordConfig(Section):
    """What is recorded (and served live), how segments rotate and how much disk they may use."""

    images: bool | None = None
    """Camera frames as `foxglove.CompressedImage`. None (the default): off for `run --record`
    (on the vehicle the driver's face is personal data), on for `replay --mcap` and for the
    live view; true or false: the same for all three."""
    image_fps: float = Field(default=5.0, gt=0)
    """Camera frames per second of the source's time at most (every frame when the source is
    slower)."""
    image_width_px: int = Field(default=640, ge=16)
    """Wider frames are scaled down to this width (the aspect kept; never scaled up); the
    annotations are scaled with them."""
    image_format: Literal["jpeg", "png"] = "jpeg"
    """`png` is lossless (a recording replayed gives the records of the video), about 25 times
    slower to encode and 10 times larger."""
    jpeg_quality: int = Field(default=80, ge=1, le=100)
    landmarks: bool = True
    """The face landmarks as points in the annotations of the frames that carry an image."""
    segment_mb: float = Field(default=256.0, gt=0)
    """`run --record`: a segment is closed and the next one opened at this size ..."""
    segment_s: float = Field(default=600.0, gt=0)
    """... or at this age, whichever comes first."""
    max_disk_mb: float = Field(default=4096.0, gt=0)
    """`run --record`: the segments in the folder use at most this much; the oldest closed
    segment is removed first (logged). At least two segments."""
    flush_s: float = Field(default=2.0, gt=0)
    """The open chunk is written out and synced to disk this often: the most a `kill -9` or a
    power loss can lose."""
    chunk_kb: int = Field(default=1024, ge=16)
    """A chunk is also written out when it holds this much (uncompressed)."""
    compression: Literal["zstd", "lz4", "none"] = "zstd"
    state_interval_s: float = Field(default=1.0, gt=0)
    """The service's state message is recorded this often (of the source's time)."""
    queue_frames: int = Field(default=256, ge=8, le=100_000)
    """Records waiting for the writer thread at most; the loop waits when it is full (a record
    is never dropped; camera frames are, and are counted)."""
    camera_topic: str | None = None
    """The channel an MCAP drive's camera frames are read from (`replay`, `batch`): None = the
    only image channel, else `/camera/image`."""
    max_chunk_mib: float = Field(default=32.0, gt=0, le=4096)
    """Reading an MCAP recording (`replay`, `batch`, `bench`, `recover`): a chunk that declares
    more than this uncompressed is refused before it is decompressed, so this setting, not the
    file, sets the memory a chunk takes. A chunk holds at least one message: an uncompressed 4K
    RGB frame (3840 x 2160 x 3 bytes, 24 MiB) fits the default."""

    @model_validator(mode="after")
    def _disk_holds_two_segments(self) -> Self:
        if self.max_disk_mb < MIN_SEGMENTS_ON_DISK * self.segment_mb:
            raise ValueError(
                f"record.max_disk_mb ({self.max_disk_mb:g}) must be at least "
                f"{MIN_SEGMENTS_ON_DISK} x record.segment_mb ({self.segment_mb:g}): the open "
                "segment and the last closed one"
            )
        return self

    def images_for(self, use: Literal["vehicle", "replay", "live"]) -> bool:
        """Whether camera frames go into this use's output (`images` None: only off on the
        vehicle's recording)."""
        if self.images is not None:
            return self.images
        return use != "vehicle"
