"""Periodic orbits of the hybrid flow: the period map, shooting and Floquet multipliers.

A periodic orbit of period ``n`` (in excitation periods ``T``) is a fixed point of the
map that takes the state at ``t = 0`` to the state at ``t = n T``
(:class:`~blademodel.orbits.period_map.PeriodMap`, the exact hybrid flow of the
compiled kernel: RK4 or RK8 with located events). :func:`find_periodic_orbit` finds
one by Newton's method on that map; the eigenvalues of the map's Jacobian (the
monodromy matrix) are the orbit's Floquet multipliers. The Jacobian is the tangent of
the flow, with saltation matrices at the events: variational equations on the
product-mode kernel (:mod:`blademodel.numeric.tangent`), the recorded run replayed through
each mode's step matrix on the per-contact kernel
(:mod:`blademodel.numeric.contact_tangent`); central differences of the map where it
fails (``docs/orbits_tangent.md``). :func:`continuation` follows a branch in a
config field; :func:`period_doubled_branch` switches to the branch born at a period
doubling, :func:`branch_point_branch` to the one that crosses it at a branch point.
"""

from .arclength import continuation
from .branch import Branch, ContinuationInterrupted, SpecialPoint
from .period_map import FlowError, PeriodMap
from .shooting import PeriodicOrbit, ShootingError, find_periodic_orbit
from .switching import branch_point_branch, period_doubled_branch

__all__ = ["Branch", "ContinuationInterrupted", "FlowError", "PeriodMap", "PeriodicOrbit", "ShootingError",
           "SpecialPoint", "branch_point_branch", "continuation", "find_periodic_orbit", "period_doubled_branch"]
