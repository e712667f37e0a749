"""The base of every message roadgaze publishes (pure: pydantic only)."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict

__all__ = ["Message"]


class Message(BaseModel):
    model_config = ConfigDict(
        frozen=True,
        populate_by_name=True,
        extra="forbid",
        json_schema_serialization_defaults_required=True,  # every field is always published
        allow_inf_nan=False,  # JSON has no NaN or Infinity; a message holding one is refused
    )

    def to_json_bytes(self) -> bytes:
        return self.model_dump_json(by_alias=True).encode("utf-8")
