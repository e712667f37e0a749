"""The driver across the frames of a stream: chosen once by the seat, then held by identity.

Pure (numpy-free). `DriverTracker.step` is called once per frame with the faces found. Under
the `seat` rule (the default):

- **Identity.** Every face is matched to the faces of the previous frames by its box: overlap
  (IoU) at least `DRIVER_MATCH_IOU`, else a centre within `MATCH_CENTRE_WIDTHS` of the earlier
  box's width and an area within `MATCH_AREA_RATIO` (a fast move between two frames). Pairs are
  taken best first, one face per track. Size decides nothing: the face matched to the driver's
  track is the driver, whatever its size or place, so a passenger is never taken for the driver
  while the driver's face is found.
- **The others.** A face seen beside the driver is someone else; its track (its last box) is
  kept `OTHER_TRACK_KEEP_S` after it was last matched. While the driver's face is lost (turned
  away, covered) such a face is not taken as the driver: the driver is then absent (the monitor
  counts the driver unavailable) rather than the passenger judged in their place.
- **The first pick**, and a new pick when the driver's face is lost and a face no track knows
  appears (the driver back at another place, or someone new): the seat rule among those faces
  (`roadgaze.landmarks.seat.seat_pick`).
- **A new pick is on probation.** The driver's track it replaced is kept `OTHER_TRACK_KEEP_S`
  after it was last matched; a face continuing it is the driver again, whatever the new pick
  shows, and the new pick becomes someone else. A false find while the driver's face is lost
  (at night, a headrest or hair found as a face above a face turned down) otherwise took the
  driver's track, and the driver, back at the road a second later, was taken for someone else
  for as long as it stayed in view.
- **A recording's choice.** When the frame comes from a recording that kept its driver's box
  (`roadgaze.types.RecordedDriver`), the driver is the face overlapping that box by at least
  `DRIVER_MATCH_IOU`, none when no face does or the recording had none: a drive and its
  recording judge the same person.

The rules "largest", "left" and "right" choose per frame as they always did (`choose_driver`;
"largest" kept while no other face is 1.25 times larger). Under every rule each frame says why
its driver cannot be told from another face in view (`roadgaze.landmarks.seat.ambiguity`, ''
when it can); the start of such a stretch is logged (a warning, at most every
`AMBIGUOUS_LOG_S`), and its end once it has been clear for `AMBIGUOUS_CLEAR_S`.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass

from roadgaze.landmarks.driver import (
    DRIVER_MATCH_IOU,
    DRIVER_RULES,
    box_iou,
    choose_driver,
    rule_side,
)
from roadgaze.landmarks.seat import (
    PLAUSIBLE_AREA_RATIO,
    Box,
    Boxed,
    ambiguity,
    area,
    centre_x,
    seat_pick,
)
from roadgaze.types import RecordedDriver

log = logging.getLogger(__name__)

MATCH_CENTRE_WIDTHS = 0.5
"""A face whose box centre lies within this many widths of a track's last box (and whose area
is within `MATCH_AREA_RATIO`) continues that track when the boxes overlap too little."""
MATCH_AREA_RATIO = 1.5
OTHER_TRACK_KEEP_S = 10.0
"""How long a face seen beside the driver is remembered after it was last matched."""
MAX_OTHER_TRACKS = 8
AMBIGUOUS_LOG_S = 10.0
"""At most one warning per this many seconds of the stream about an ambiguous driver."""
AMBIGUOUS_CLEAR_S = 1.0


@dataclass(slots=True)
class _Track:
    box_px: Box
    seen_t_s: float


def _likeness(track: Box, face: Box) -> float:
    """How well `face` continues `track`: > 1 by overlap, in (0, 1] by nearness, 0 not at all."""
    overlap = box_iou(track, face)
    if overlap >= DRIVER_MATCH_IOU:
        return 1.0 + overlap
    width = track[2] - track[0]
    ratio = area(face) / max(area(track), 1e-9)
    if width <= 0 or not 1.0 / MATCH_AREA_RATIO <= ratio <= MATCH_AREA_RATIO:
        return 0.0
    reach = MATCH_CENTRE_WIDTHS * width
    distance = math.hypot(
        centre_x(face) - centre_x(track), 0.5 * (face[1] + face[3] - track[1] - track[3])
    )
    return 0.0 if distance > reach else 1.0 - 0.999 * distance / reach


def match(tracks: Sequence[Box], faces: Sequence[Box]) -> dict[int, int]:
    """{face index: track index}: each face continuing a track, best pairs first."""
    pairs = [
        (likeness, face, track)
        for track, track_box in enumerate(tracks)
        for face, face_box in enumerate(faces)
        if (likeness := _likeness(track_box, face_box)) > 0.0
    ]
    matched: dict[int, int] = {}
    taken: set[int] = set()
    for _, face, track in sorted(pairs, reverse=True):
        if face not in matched and track not in taken:
            matched[face] = track
            taken.add(track)
    return matched


class DriverTracker:
    """The driver's choice in a stream under `rule`, `seat_side` as `driver_image_side` gives it
    (see the module doc). `box_px` is the driver's box on the last frame (None: no driver)."""

    def __init__(self, rule: str, seat_side: int) -> None:
        if rule not in DRIVER_RULES:
            raise ValueError(f"unknown driver rule '{rule}'; choose {', '.join(DRIVER_RULES)}")
        self.rule = rule
        self.side = rule_side(rule, seat_side)
        self.box_px: Box | None = None
        self._driver: _Track | None = None
        self._replaced: _Track | None = None
        """The driver's track a new pick replaced (see the module doc), until it is too old."""
        self._others: list[_Track] = []
        self.ambiguous = ""
        self._warned_t_s = -math.inf
        self._clear_since_t_s: float | None = None
        self._told = False

    def step(
        self, faces: Sequence[Boxed], t_s: float, recorded: RecordedDriver | None = None
    ) -> int | None:
        """The driver's index among this frame's `faces` (None: no driver); `ambiguous` says
        why it cannot be told from another face ('' when it can)."""
        boxes = [face.box_px for face in faces]
        if recorded is not None:
            index = _overlapping(boxes, recorded.box_px)
        elif self.rule != "seat":
            index = choose_driver(faces, self.rule, self.box_px)
        else:
            index = self._seat_step(boxes, t_s)
        self._remember(boxes, index, t_s)
        self._note_ambiguity(ambiguity(faces, index, self.rule, self.side), t_s)
        return index

    def _seat_step(self, boxes: list[Box], t_s: float) -> int | None:
        self._others = [t for t in self._others if t_s - t.seen_t_s <= OTHER_TRACK_KEEP_S]
        replaced = self._replaced
        if replaced is not None and t_s - replaced.seen_t_s > OTHER_TRACK_KEEP_S:
            replaced = self._replaced = None
        tracks = [track.box_px for track in self._others]
        driver_track = replaced_track = -1
        if self._driver is not None:
            driver_track = len(tracks)
            tracks.append(self._driver.box_px)
        if replaced is not None:
            replaced_track = len(tracks)
            tracks.append(replaced.box_px)
        matched = match(tracks, boxes)
        for face, track in matched.items():
            if track == replaced_track:  # the driver before the new pick: the driver again
                if self._driver is not None:
                    self._others.append(self._driver)
                self._driver, self._replaced = replaced, None
                return face
        for face, track in matched.items():
            if track == driver_track:
                return face
        # Faces no track knows, of a size that could be the driver's among all in view.
        least_px2 = PLAUSIBLE_AREA_RATIO * max(area(box) for box in boxes) if boxes else 0.0
        unknown = [
            face
            for face in range(len(boxes))
            if face not in matched and area(boxes[face]) >= least_px2
        ]
        chosen = seat_pick([_Boxed(boxes[face]) for face in unknown], self.side)
        if chosen is None:
            return None
        if self._driver is not None and self._replaced is None:  # the driver's face is lost
            self._replaced = self._driver  # (on a second new pick, the first driver is kept)
        return unknown[chosen]

    def _remember(self, boxes: list[Box], index: int | None, t_s: float) -> None:
        """The driver's track and the others' after this frame's choice."""
        self.box_px = None if index is None else boxes[index]
        if index is not None:
            self._driver = _Track(boxes[index], t_s)
        if self.rule != "seat":
            return
        others = self._others
        matched = match([track.box_px for track in others], boxes)
        for face, box in enumerate(boxes):
            if face == index:
                continue
            if face in matched:
                others[matched[face]] = _Track(box, t_s)
            elif self.box_px is None or box_iou(box, self.box_px) < DRIVER_MATCH_IOU:
                others.append(_Track(box, t_s))  # (a second find of the driver's face is not)
        kept = [track for track in others if t_s - track.seen_t_s <= OTHER_TRACK_KEEP_S]
        if index is not None:  # the driver's face is nobody else's
            kept = [track for track in kept if box_iou(track.box_px, boxes[index]) < 0.5]
        self._others = sorted(kept, key=lambda track: track.seen_t_s)[-MAX_OTHER_TRACKS:]

    def _note_ambiguity(self, reason: str, t_s: float) -> None:
        if reason:
            self._clear_since_t_s = None
            if reason != self.ambiguous and t_s - self._warned_t_s >= AMBIGUOUS_LOG_S:
                log.warning("driver ambiguous from t=%.2f s: %s", t_s, reason)
                self._warned_t_s, self._told = t_s, True
        elif self._told:
            if self._clear_since_t_s is None:
                self._clear_since_t_s = t_s
            elif t_s - self._clear_since_t_s >= AMBIGUOUS_CLEAR_S:
                log.info("driver clear again from t=%.2f s", self._clear_since_t_s)
                self._told = False
        self.ambiguous = reason


@dataclass(frozen=True, slots=True)
class _Boxed:
    box_px: Box


def _overlapping(boxes: list[Box], box: Box | None) -> int | None:
    """The face overlapping `box` most, if by at least `DRIVER_MATCH_IOU`."""
    if box is None or not boxes:
        return None
    overlaps = [box_iou(face, box) for face in boxes]
    best = max(range(len(boxes)), key=overlaps.__getitem__)
    return best if overlaps[best] >= DRIVER_MATCH_IOU else None
