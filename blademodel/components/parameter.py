"""Named numeric parameters shared between components.

A component parameter is either a plain number, which gets a default symbol name
derived from the component, or a :class:`Param`, which fixes the symbol name. Two
components that use a :class:`Param` of the same name share one symbol, so one
value drives both (the excitation frequency of the two blades, say).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Union

from ._sympy import sp


@dataclass(frozen=True)
class Param:
    """A numeric value with the symbol name it carries in the equations.

    Parameters
    ----------
    name : str
        Symbol name, a valid Python identifier (``"kx"``, ``"omega"``).
    value : float
        Numeric value in SI units.
    """

    name: str
    value: float

    def __post_init__(self):
        if not self.name.isidentifier():
            raise ValueError(f"parameter name {self.name!r} is not a valid identifier")
        value = float(self.value)
        if not math.isfinite(value):
            raise ValueError(f"parameter {self.name} = {self.value!r} is not finite")
        object.__setattr__(self, "value", value)

    @property
    def symbol(self) -> sp.Symbol:
        """The SymPy symbol of this parameter (real)."""
        return sp.Symbol(self.name, real=True)


Number = Union[float, int, Param]


def as_param(value: Number, default_name: str, *, field: str, minimum: float | None = None,
             strict: bool = False) -> Param:
    """Return ``value`` as a :class:`Param`, checking it is finite and in range.

    Parameters
    ----------
    value : float or Param
        The value given by the user.
    default_name : str
        Symbol name used when ``value`` is a plain number.
    field : str
        Name of the field, used in error messages.
    minimum : float, optional
        Lower bound; ``strict`` makes it exclusive.
    """
    if not isinstance(value, Param):
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"{field} = {value!r} is not a number") from None
        if not math.isfinite(number):
            raise ValueError(f"{field} = {value!r} is not finite")
    p = value if isinstance(value, Param) else Param(default_name, value)
    if minimum is not None:
        if strict and not p.value > minimum:
            raise ValueError(f"{field} = {p.value!r} must be > {minimum}")
        if not strict and not p.value >= minimum:
            raise ValueError(f"{field} = {p.value!r} must be >= {minimum}")
    return p
