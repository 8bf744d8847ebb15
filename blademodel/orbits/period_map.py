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
        mode = settle(ig, full, mode)
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


def settle(integrator, y, mode):
    """The mode ``y`` starts in: ``mode`` with every guard already past zero at ``t = 0`` fired.

    The kernels fire a guard when it *crosses* zero within a step; a start state that
    already lies past one (a section state on the far side of a stick-slip or contact
    boundary of ``mode``) would otherwise follow ``mode``'s flow. Firing it makes the
    period map continuous across the boundary, which shooting and continuation cross
    when the orbit's switching time passes the section. The product-mode kernel only:
    the per-contact kernel's guard functions are not callable from Python, and there
    the mode is taken as given. ``y`` may be reset in place (a transition's reset).
    """
    if isinstance(mode, np.ndarray) or not hasattr(integrator, "module"):
        return mode
    mod = integrator.module
    g = np.empty(mod.GUARD_DIR.shape[1] + 1)
    tmp = np.empty(y.shape[0])
    for _ in range(4):
        mod.guards(mode, 0.0, y, integrator.p, g)
        past = [i for i in range(mod.N_GUARDS[mode])
                if (mod.GUARD_DIR[mode, i] < 0 and g[i] < 0.0) or (mod.GUARD_DIR[mode, i] > 0 and g[i] > 0.0)]
        if not past:
            break
        mode = int(mod.transition(mode, past[0], 0.0, y, integrator.p, tmp))
    return mode


def _copy(mode):
    """A mode the kernel may update in place (the per-contact kernel's is an array)."""
    return mode.copy() if isinstance(mode, np.ndarray) else mode
