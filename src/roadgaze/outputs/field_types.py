"""The types of the record's fields and the rounding of its numbers (`roadgaze.outputs.records`
re-exports both: import them from there)."""

from __future__ import annotations

import math
from enum import StrEnum


class FieldType(StrEnum):
    """The type of one field of a record; every field may also be None (null)."""

    BOOL = "bool"
    INT = "int"
    FLOAT = "float"
    STR = "str"
    STR_LIST = "list[str]"
    HANDS = "list[hand]"
    """Each hand found (`roadgaze.outputs.hand_record.hand_landmarks`): nested, so it is no CSV
    column."""


def rounded(value: float | None, digits: int) -> float | None:
    """`value` rounded for a record; None for None, NaN or infinity."""
    if value is None or not math.isfinite(value):
        return None
    return round(float(value), digits)
