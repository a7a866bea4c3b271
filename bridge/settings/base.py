"""The base of every settings table: unknown keys refused, and no boolean where a number goes.

Rules:
1. Every table's model derives from ``Strict`` (the top level, a BaseSettings, calls
   ``numbers_not_booleans`` itself): an unknown key is an error (settings/ rule 1).
2. A key that takes a number (``int`` or ``float``, also with None, or in a list, a tuple or a
   table's values) refuses ``true`` and ``false``: pydantic's lax mode reads them as 1 and 0,
   so ``port = true`` connected to port 1 and ``park_az_deg = true`` parked at 1 degree (an
   attack pass). A number written as text (``"60"``, what the environment gives) is still read
   as one; a key that takes a boolean as well is left alone.
"""

from __future__ import annotations

import types
from typing import Annotated, Any, Union, get_args, get_origin

from pydantic import BaseModel, ConfigDict, ValidationInfo, field_validator

_NUMBERS = (int, float)


def takes_boolean_for_number(annotation: Any, value: Any) -> bool:
    """Whether ``value`` holds a boolean where ``annotation`` wants a number (rule 2)."""
    origin, args = get_origin(annotation), get_args(annotation)
    if origin is Annotated:
        return takes_boolean_for_number(args[0], value)
    if origin in (Union, types.UnionType):
        if isinstance(value, bool):
            kinds = [get_args(a)[0] if get_origin(a) is Annotated else a for a in args]
            return bool not in kinds and any(k in _NUMBERS for k in kinds)
        return any(takes_boolean_for_number(a, value) for a in args)
    if isinstance(value, bool):
        return annotation in _NUMBERS
    if origin in (list, set, frozenset) and isinstance(value, list | tuple | set):
        return any(takes_boolean_for_number(args[0], v) for v in value)
    if origin is tuple and isinstance(value, list | tuple):
        each = [args[0]] * len(value) if len(args) == 2 and args[1] is ... else args
        return any(takes_boolean_for_number(a, v) for a, v in zip(each, value, strict=False))
    if origin is dict and isinstance(value, dict) and len(args) == 2:
        return any(takes_boolean_for_number(args[1], v) for v in value.values())
    return False


def numbers_not_booleans(cls: type[BaseModel], value: Any, info: ValidationInfo) -> Any:
    """A before-validator for every field (rule 2); ValueError names no value."""
    field = cls.model_fields.get(info.field_name or "")
    if field is not None and takes_boolean_for_number(field.annotation, value):
        raise ValueError("must be a number, not true or false")
    return value


class Strict(BaseModel):
    """Rule 1."""

    model_config = ConfigDict(extra="forbid")

    _numbers_not_booleans = field_validator("*", mode="before")(numbers_not_booleans)
