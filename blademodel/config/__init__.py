"""Validated configs: the paper's blade pair and the generic component format."""

from .blade_pair import BladePair, BladeValues

__all__ = ["BladePair", "BladeValues"]
