"""Field types of the component-list format: numbers or parameter names.

A numeric field of a component may hold a number or the name of a parameter
declared under ``parameters:``. YAML 1.1 (PyYAML) reads ``1e5`` as a string, so a
string that parses as a number is a number.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Annotated, Any, Optional, Union

from pydantic import BeforeValidator, PlainValidator
from pydantic_core import PydanticCustomError


@dataclass(frozen=True)
class Bound:
    """Lower bound of a numeric field: ``gt`` (exclusive) or ``ge`` (inclusive)."""

    gt: Optional[float] = None
    ge: Optional[float] = None

    def error(self, x: float) -> Optional[PydanticCustomError]:
        """The error for ``x`` out of range, or ``None`` if it is in range."""
        if self.gt is not None and not x > self.gt:
            return PydanticCustomError("greater_than", "Input should be greater than {gt}", {"gt": self.gt})
        if self.ge is not None and not x >= self.ge:
            return PydanticCustomError("greater_than_equal", "Input should be greater than or equal to {ge}",
                                       {"ge": self.ge})
        return None


def _not_a_number():
    return PydanticCustomError("number_or_name", "Input should be a number or the name of a parameter")


def parse_number_or_name(value: Any, bound: Bound = Bound()) -> Union[float, str]:
    """A finite number in range, or an identifier naming a parameter.

    Raises
    ------
    pydantic_core.PydanticCustomError
        With a message in pydantic's wording.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise _not_a_number()
    if isinstance(value, str):
        text = value.strip()
        try:
            x = float(text)
        except ValueError:
            if text.isidentifier():
                return text
            raise _not_a_number() from None
    else:
        x = float(value)
    if not math.isfinite(x):
        raise PydanticCustomError("finite_number", "Input should be a finite number")
    err = bound.error(x)
    if err is not None:
        raise err
    return x


def number(*, gt: Optional[float] = None, ge: Optional[float] = None, optional: bool = False):
    """Annotated type of a numeric field that may name a parameter instead.

    Parameters
    ----------
    gt, ge : float, optional
        Exclusive / inclusive lower bound, checked on numbers here and on the
        parameter's value when the field names a parameter.
    optional : bool
        Also accept ``None`` (a field left out; a dumped config holds it as ``null``).
    """
    b = Bound(gt, ge)
    if optional:
        return Annotated[Optional[Union[float, str]],
                         PlainValidator(lambda v: None if v is None else parse_number_or_name(v, b)), b]
    return Annotated[Union[float, str], PlainValidator(lambda v: parse_number_or_name(v, b)), b]


def field_bound(field_info) -> Optional[Bound]:
    """The :class:`Bound` of a field made with :func:`number`, else ``None``."""
    return next((m for m in field_info.metadata if isinstance(m, Bound)), None)


def _int_to_str(v):
    return str(v) if isinstance(v, int) and not isinstance(v, bool) else v


#: A name that YAML may read as an integer (mass ``1``).
Name = Annotated[str, BeforeValidator(_int_to_str)]
