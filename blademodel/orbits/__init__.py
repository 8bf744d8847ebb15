"""Periodic orbits of the hybrid flow: the period map, shooting and Floquet multipliers.

A periodic orbit of period ``n`` (in excitation periods ``T``) is a fixed point of the
map that takes the state at ``t = 0`` to the state at ``t = n T``
(:class:`~blademodel.orbits.period_map.PeriodMap`, the exact hybrid flow of the
compiled kernel: RK4 or RK8 with located events). :func:`find_periodic_orbit` finds
one by Newton's method on that map; the eigenvalues of the map's Jacobian (the
monodromy matrix) are the orbit's Floquet multipliers. The Jacobian is taken by
central differences of the map (``docs/orbits.md``).
"""

from .arclength import Branch, SpecialPoint, continuation
from .period_map import FlowError, PeriodMap
from .shooting import PeriodicOrbit, ShootingError, find_periodic_orbit

__all__ = ["Branch", "FlowError", "PeriodMap", "PeriodicOrbit", "ShootingError", "SpecialPoint", "continuation",
           "find_periodic_orbit"]
