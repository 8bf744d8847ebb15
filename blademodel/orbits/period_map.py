"""The map from a state at ``t = 0`` to the state ``n`` excitation periods later, and its Jacobian."""

from __future__ import annotations

import numpy as np


class FlowError(RuntimeError):
    """The integration behind the period map stopped early (status and message of the kernel)."""


class PeriodMap:
    """``P(y) = `` the state ``periods`` excitation periods after ``(y, mode)`` at ``t = 0``.

    The forcing is ``T``-periodic, so the map is the same from any whole period;
    ``y`` holds the physical states only (coordinates, velocities, friction-law
    states; no energy accumulators).

    Parameters
    ----------
    integrator : Integrator
        From :func:`blademodel.numeric.kernels.make_integrator` (either kernel).
    periods : int
        ``n``: the map covers ``n T``.
    """

    def __init__(self, integrator, periods: int = 1):
        if int(periods) < 1:
            raise ValueError(f"periods must be a whole number >= 1, got {periods!r}")
        self.integrator = integrator
        self.periods = int(periods)
        self.n = integrator.n_physical
        self.evaluations = 0

    def __call__(self, y, mode):
        """The state and mode ``n T`` after ``(y, mode)``."""
        ig = self.integrator
        full = np.zeros(ig.n_state)
        full[:self.n] = y
        status, mode_end, t = ig.advance(full, mode, 0, self.periods)
        self.evaluations += 1
        if status != 0:
            raise FlowError(f"the integration stopped at t = {t:.6g} s with status {status}")
        return full[:self.n].copy(), mode_end

    def jacobian(self, y, mode, scale, rel_step: float = 1e-6) -> np.ndarray:
        """``dP/dy`` at ``(y, mode)`` by central differences, column ``i`` with step ``rel_step * scale[i]``.

        Every perturbed start keeps ``mode``: the map is differentiated along the
        event sequence of ``(y, mode)``, which is what its eigenvalues describe as
        long as no event of the orbit is grazing (a perturbation of ``rel_step``
        would then change the sequence).
        """
        y = np.asarray(y, dtype=float)
        J = np.empty((self.n, self.n))
        for i in range(self.n):
            d = rel_step * scale[i]
            yp, ym = y.copy(), y.copy()
            yp[i] += d
            ym[i] -= d
            J[:, i] = (self(yp, _copy(mode))[0] - self(ym, _copy(mode))[0]) / (2.0 * d)
        return J


def _copy(mode):
    """A mode the kernel may update in place (the per-contact kernel's is an array)."""
    return mode.copy() if isinstance(mode, np.ndarray) else mode
