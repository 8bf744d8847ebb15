"""Frictionless contact: the tangential direction carries no force."""

from __future__ import annotations

from dataclasses import dataclass

from .._sympy import sp

from .base import ContactContext, FrictionLaw


@dataclass(frozen=True)
class NoFriction(FrictionLaw):
    """No friction: a closed contact has one mode, ``closed``, with ``f = 0``."""

    modes = ("closed",)

    def parameters(self):
        return {}

    def force(self, mode, ctx: ContactContext):
        return sp.Integer(0)

    def guards(self, mode, ctx):
        return []

    def entry(self, ctx):
        from .base import Candidate
        return [Candidate("closed")]
