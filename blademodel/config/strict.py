"""The base of the configs with named fields: no extra keys, no NaN, no booleans as numbers.

Pydantic's lax mode reads ``true`` as ``1.0`` in a ``float`` field (and as ``1`` in
an ``int`` one), so ``--set gamma=true`` (or ``gamma: yes`` in YAML 1.1) would
silently give ``gamma = 1``. :class:`StrictConfig` refuses a boolean in any field
whose type holds numbers and no booleans, naming the field and the value.
"""

from __future__ import annotations

import typing
from typing import Any

from pydantic import BaseModel, ConfigDict, ValidationInfo, field_validator


def _leaves(annotation) -> set:
    """The plain types an annotation is built of (through Optional, Union, list, Annotated)."""
    origin = typing.get_origin(annotation)
    if origin is None:
        return {annotation}
    if origin is typing.Annotated:
        return _leaves(typing.get_args(annotation)[0])
    if origin is typing.Literal:
        return {type(a) for a in typing.get_args(annotation)}
    out: set = set()
    for arg in typing.get_args(annotation):
        if arg is not Ellipsis:
            out |= _leaves(arg)
    return out


def numeric_only(annotation) -> bool:
    """Whether a field of this type takes numbers but no booleans (``float``, ``list[float]``...)."""
    leaves = _leaves(annotation)
    return bool(leaves & {int, float}) and not leaves & {bool, Any, object}


def _has_bool(value: Any) -> bool:
    if isinstance(value, bool):
        return True
    return isinstance(value, (list, tuple)) and any(isinstance(v, bool) for v in value)


class StrictConfig(BaseModel):
    """Pydantic base of the configs: extra keys, NaN/inf and booleans given as numbers are errors."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_assignment=True)

    @field_validator("*", mode="before")
    @classmethod
    def _no_boolean_numbers(cls, value: Any, info: ValidationInfo) -> Any:
        field = cls.model_fields.get(info.field_name) if info.field_name else None
        if field is not None and _has_bool(value) and numeric_only(field.annotation):
            raise ValueError("expected a number, got a boolean (true/false is not a number)")
        return value
