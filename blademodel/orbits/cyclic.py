"""The travelling-wave symmetry of a tuned bladed disk: its orbits from a fraction of a period.

A tuned ring of ``N`` blades driven in engine order ``EO`` (blade ``i``'s force
``F0 sin(omega t + phase0 + 2 pi EO i / N)``) is the same after turning it by ``s``
blades and shifting time by ``tau = (s EO mod N) T / N``: blade ``i + s``'s force is
blade ``i``'s, ``tau`` later. The smallest shift is ``tau = g T / N``, ``g = gcd(EO, N)``,
for the ``s`` with ``s EO = g (mod N)``. A travelling-wave orbit has the symmetry itself,
``x_{i+s}(t) = x_i(t + tau)``, so its state at ``t = 0`` is a fixed point of the reduced map

    G(y) = S^s Phi(0 -> tau)(y),

``S`` the turn by one blade (blade ``i``'s states, and contact ``i``'s, to slot ``i + 1``):
``d = N / g`` times fewer steps than the period map (eight on the 24-blade ring at engine
order 3). Its derivative ``J = S^s dPhi`` gives the ring's monodromy exactly: ``G^d = S^(s d)
Phi(0 -> T)``, so ``M = S^(-s d) J^d``, whose eigenvalues are the Floquet multipliers of
the orbit in the whole ring (perturbations that break the symmetry included: ``S^(s d)``
permutes the blades, and so ``J``'s own eigenvalues, raised to ``d``, are the multipliers
only up to the phase of that permutation on their eigenvectors; their moduli agree).

The orbit over a whole period is the reduced run's, each ``tau`` turned by ``s`` blades
more: ``x_i(k tau + t) = x_{i + k s}(t)``.

Only orbits that have the symmetry are found this way: a branch that breaks it (where a
multiplier of ``M`` crosses the unit circle with an eigenvector of another symmetry) goes
on as the travelling wave, and the branch it meets there is not followed on the reduced
map. The one exception: at a period doubling where ``J`` itself has the eigenvalue ``+1``
(on a perturbation that ``S^(s d)`` reverses), the doubled orbits are fixed points of
``G`` that come back after one period turned by ``s d`` blades, and
:func:`~blademodel.orbits.period_doubled_branch` follows them on ``G`` (``periods = 2``
here: the run rebuilt over ``2 T``, the monodromy ``S^(-2 s d) J^(2 d)``).
"""

from __future__ import annotations

import copy
import math
import re

import numpy as np


class CyclicError(ValueError):
    """The model has no travelling-wave symmetry to reduce by (or not one this module can use)."""


class CyclicSymmetry:
    """The turn-and-shift symmetry of a tuned bladed disk (see the module docstring).

    Parameters
    ----------
    config : BladedDisk
        The ring's config: tuned (no mistuning, no single blade's or contact's values),
        its engine order not a multiple of its number of blades.
    integrator : ContactIntegrator
        Its integrator (the state's and contacts' names and order are read from it).
    periods : int
        The whole ring's period of the orbits followed, in excitation periods. A fixed
        point ``y`` of the reduced map comes back after ``T`` turned, ``Phi(0 -> T)(y) =
        S^(-s d) y``: a travelling wave of period ``T`` has ``S^(s d) y = y``; the
        period-doubled orbits born where the reduced map has a branch point (``J`` with
        the eigenvalue ``+1`` on a perturbation that ``S^(s d)`` reverses) have
        ``S^(2 s d) y = y`` and period ``2 T`` (:meth:`comes_back`). The orbit's run and
        monodromy are over ``periods`` excitation periods.
    every : int
        Keep only every ``every``-th power of the turn: the turn by ``every s`` blades with
        the shift ``every tau``, whose map ``G^every`` covers ``every T / d``
        (``d / every`` times fewer steps than the period map; ``every`` must divide ``d``).
        Its fixed points are the orbits with that symmetry, the travelling waves among them:
        the orbits born where ``J`` has the eigenvalue ``-1`` (``G`` period-doubles, the
        whole ring's ``M`` shows ``+1``: a branch point of the travelling waves) have it for
        ``every = 2`` (:func:`~blademodel.orbits.branch_point_branch`).

    Raises
    ------
    CyclicError
        Naming the field that breaks the symmetry, or where the steps of a period do not
        divide into the reduced map's.
    """

    def __init__(self, config, integrator, periods: int = 1, every: int = 1):
        if int(periods) < 1:
            raise ValueError(f"periods must be a whole number >= 1, got {periods!r}")
        self.periods = int(periods)
        N, EO, g = reducible(config)
        self.blades = N
        d = N // g
        if int(every) < 1 or d % int(every):
            raise CyclicError(f"every = {every!r}: the map keeps every k-th power of the turn for k dividing "
                              f"N / gcd(EO, N) = {d}")
        self.every = int(every)
        self.fraction = d // self.every                          # the reduced map covers T / fraction
        s = next(s for s in range(1, N) if (s * EO) % N == g)
        self.turn = (self.every * s) % N                         # the turn it is taken with
        S = int(integrator.steps_per_period)
        if S % self.fraction:
            raise CyclicError(f"steps_per_period = {S} is not a multiple of {self.fraction}: the reduced map "
                              f"covers T / {self.fraction} in whole steps (--steps-per-period "
                              f"{-(-S // self.fraction) * self.fraction} would do)")
        self.n = int(integrator.n_physical)
        self.discrete = np.asarray(getattr(integrator, "discrete_states", ()), dtype=np.int64)   # the laws' labels
        self.index = _turned(list(integrator.meta["state"])[:self.n], N, self.turn)        # states
        self.contact_index = _turned(list(integrator.meta["contacts"]), N, self.turn)    # contact modes
        # the slot each entry reaches after k turns, k = 0 .. d: rows of powers of the turn
        powers = [np.arange(self.n)]
        for _ in range(self.periods * self.fraction):
            powers.append(self.index[powers[-1]])
        self._powers = powers

    def reduced(self, integrator):
        """``integrator`` over ``tau = T / d`` in ``S / d`` steps (the same step): the reduced map's. A copy (its
        :attr:`~blademodel.numeric.contact_kernel.ContactIntegrator.period_fraction` ``d``, so that its copies with
        other parameter values stay reduced), or ``integrator`` itself where it is one already."""
        f = getattr(integrator, "period_fraction", 1)   # (another reduction's integrator: from its whole period)
        if f == self.fraction:
            return integrator
        new = copy.copy(integrator)
        new.period = integrator.period * f / self.fraction
        new.steps_per_period = integrator.steps_per_period * f // self.fraction
        new.period_fraction = self.fraction
        new._pack()   # its tables (the forcing's phase table is for a whole period: none over a fraction)
        return new

    # --- the turn ---------------------------------------------------------------------------
    def turned(self, y: np.ndarray) -> np.ndarray:
        """``S^s y``: each blade's (and contact's) states moved ``s`` slots on; the leading ``n`` entries only."""
        out = np.empty(self.n)
        out[self.index] = y[:self.n]
        return out

    def turned_modes(self, cm: np.ndarray) -> np.ndarray:
        """``S^s`` of the contacts' modes."""
        out = np.empty_like(cm)
        out[self.contact_index] = cm
        return out

    def jacobian(self, dphi: np.ndarray) -> np.ndarray:
        """``dG/dy = S^s dPhi`` from ``dPhi`` (physical states by physical states)."""
        J = np.empty_like(dphi)
        J[self.index] = dphi
        return J

    def monodromy(self, J: np.ndarray) -> np.ndarray:
        """The ring's monodromy over the orbit's ``p = periods`` periods, ``S^(-s d p) J^(d p)``, from the reduced
        map's Jacobian ``J`` at a fixed point (``G^(d p) = S^(s d p) Phi(0 -> p T)``). Not ``(S^(-s d) J^d)^p``
        where ``p > 1``: ``S^(s d)`` does not leave such an orbit's state as it is, nor ``J`` with it."""
        k = self.periods * self.fraction
        return np.linalg.matrix_power(J, k)[self._powers[k]]

    def comes_back(self, y: np.ndarray, scale: np.ndarray) -> float:
        """How far ``S^(s d periods) y`` lies from ``y`` (the largest difference over ``scale``): zero for a fixed
        point of the reduced map that is an orbit of ``periods`` excitation periods.

        At least 1 where a friction law's discrete state (an Iwan element's label) differs from
        the one it is turned onto (:func:`~blademodel.orbits.shooting.residual_size`): scaled by
        :data:`~blademodel.orbits.shooting.LABEL_SCALE`, a label that differs by 1 would
        otherwise read as ``1e-12``. The labels are read as whole numbers, as the map reads them
        (:func:`~blademodel.orbits.shooting.scaled_residual`): a corrected point's labels carry the
        rounding of its scaling (``1e-11`` on the preloaded 24-blade Iwan ring).
        """
        from .shooting import residual_size
        y = np.array(y[:self.n], dtype=float)
        d = self.discrete
        y[d] = np.rint(y[d])
        return residual_size((y[self._powers[-1]] - y) / scale, d)

    # --- the orbit over a whole period --------------------------------------------------------
    def whole_period(self, Y: np.ndarray) -> np.ndarray:
        """The orbit over ``[0, periods T]`` from the reduced run's ``Y`` over ``[0, tau]`` (rows: steps, ``t = 0``
        and ``tau`` included; columns: physical states), each ``tau`` turned by ``s`` blades more: ``x_i(k tau + t)
        = x_{i + k s}(t)``, whose entries are those that ``i``'s reach after ``k`` turns."""
        steps = Y.shape[0] - 1
        d = self.periods * self.fraction
        out = np.empty((d * steps + 1, Y.shape[1]))
        for k in range(d):
            out[k * steps:(k + 1) * steps] = Y[:steps][:, self._powers[k]]
        out[-1] = Y[steps][self._powers[d - 1]]
        return out


def what_differs(config) -> str | None:
    """What makes a bladed disk's blades or contacts differ (its mistuning, or single blades' or contacts' values),
    or None for a tuned ring."""
    if np.any(config.deviations != 0.0):
        value = config.mistuning if config.mistuning is not None else config.mistuning_std
        return f"mistuning / mistuning_std = {value!r} makes the blades differ"
    for name in ("blade_values", "contacts"):
        if getattr(config, name):
            return f"{name} = {getattr(config, name)!r} makes single blades or contacts differ"
    return None


def reducible(config) -> tuple[int, int, int]:
    """``(N, EO, g)`` of a bladed disk's config that the cyclic reduction can take (``g = gcd(EO, N)``; the reduced
    map covers ``T / (N / g)``).

    Raises
    ------
    CyclicError
        Naming the field that breaks the symmetry (or that the config is no bladed disk).
    """
    from ..config import BladedDisk
    if not isinstance(config, BladedDisk):
        raise CyclicError(f"the cyclic reduction needs a bladed disk (model: bladed_disk), not "
                          f"{type(config).__name__}")
    N, EO = int(config.blades), int(config.engine_order)
    differing = what_differs(config)
    if differing is not None:
        raise CyclicError(f"the cyclic reduction needs a tuned ring: {differing}")
    g = math.gcd(EO, N)
    if g == N:
        raise CyclicError(f"engine_order = {EO} drives every blade in phase (a multiple of blades = {N}): "
                          f"the symmetry shifts no time, and nothing is reduced")
    return N, EO, g


def _turned(names: list, N: int, s: int) -> np.ndarray:
    """``index[j]``: the slot that entry ``j`` (named ``names[j]``) moves to when the ring turns by ``s`` blades.

    Blade ``k``'s states end in ``k`` (``x3``, ``vy3``: blade 2, from 0), contact ``j``'s
    in ``c<j>`` (``z_c3``, ``s2_c3``; and the contact itself ``c3``).

    Raises
    ------
    CyclicError
        Where a name is not of either form, or a turned name does not exist.
    """
    where = {name: j for j, name in enumerate(names)}
    index = np.empty(len(names), dtype=np.int64)
    for j, name in enumerate(names):
        m = re.fullmatch(r"(.*c)(\d+)", name) or re.fullmatch(r"([A-Za-z_]*?)(\d+)", name)
        if m is None:
            raise CyclicError(f"the state or contact {name!r} belongs to no blade or contact")
        k = (int(m.group(2)) - 1 + s) % N + 1
        target = f"{m.group(1)}{k}"
        if target not in where:
            raise CyclicError(f"turning the ring by {s} blades takes {name!r} to {target!r}, which does not exist")
        index[j] = where[target]
    if np.unique(index).size != index.size:
        raise CyclicError("turning the ring does not permute its states")
    return index
