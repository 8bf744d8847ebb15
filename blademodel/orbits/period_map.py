"""The map from a state at ``t = 0`` to the state ``n`` excitation periods later, and its Jacobian."""

from __future__ import annotations

import numpy as np

#: How a :class:`PeriodMap` differentiates: ``"auto"`` (the tangent where the kernel has one, else
#: differences), ``"tangent"`` (variational equations and saltation matrices, or an error) or
#: ``"differences"`` (central differences of the map).
JACOBIAN_METHODS = ("auto", "tangent", "differences")


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
    jacobian : {"auto", "tangent", "differences"}
        How :meth:`jacobian` differentiates. The tangent (:mod:`blademodel.numeric.tangent`:
        the exact derivative of the kernel's discrete flow, saltation matrices at the
        events) exists for the product-mode kernel; ``"auto"`` takes it there and falls
        back to central differences elsewhere, or where the tangent fails (an event
        with a zero guard rate).
    """

    def __init__(self, integrator, periods: int = 1, jacobian: str = "auto"):
        if int(periods) < 1:
            raise ValueError(f"periods must be a whole number >= 1, got {periods!r}")
        if jacobian not in JACOBIAN_METHODS:
            raise ValueError(f"jacobian = {jacobian!r} must be one of {', '.join(JACOBIAN_METHODS)}")
        product = getattr(integrator, "kernel", "") == "product"
        if jacobian == "tangent" and not product:
            raise ValueError("jacobian = 'tangent' needs the product-mode kernel (models with at most one contact)")
        self.integrator = integrator
        self.periods = int(periods)
        self.n = integrator.n_physical
        self.evaluations = 0
        self.method = jacobian
        self.exact = jacobian != "differences" and product

    def derivatives(self, y, mode, dp=None, dperiod: float = 0.0):
        """``P(y)``, its mode, ``dP/dy`` and (with ``dp``) ``dP/dlambda`` by the tangent of the flow.

        Parameters
        ----------
        y : array_like
            Physical start state.
        mode : int
        dp : array_like, optional
            The direction ``d p / d lambda`` in the raw parameters.
        dperiod : float
            ``d T / d lambda``.

        Returns
        -------
        FlowSensitivity
            With ``state`` the map's value (:class:`blademodel.numeric.tangent.FlowSensitivity`).

        Raises
        ------
        SensitivityError
            Where the tangent cannot follow the flow.
        """
        from ..numeric.tangent import flow_sensitivity, settle_jacobian
        ig = self.integrator
        full = np.zeros(ig.n_state)
        full[:self.n] = y
        fired: list = []
        mode = settle(ig, full, mode, fired)
        s = flow_sensitivity(ig, full[:self.n], mode, self.periods, dp=dp, dperiod=dperiod)
        self.evaluations += 1
        if fired:
            D, dl = settle_jacobian(ig, fired, dp)
            if s.parameter is not None:
                s.parameter = s.parameter + s.monodromy @ dl
            s.monodromy = s.monodromy @ D
        return s

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

    def linearize(self, y, mode, scale, rel_step: float = 1e-6):
        """``P(y)``, the mode it ends in and ``dP/dy``: one tangent run, or the map and its differences."""
        if self.exact:
            s = self.try_derivatives(y, mode)
            if s is not None:
                return s.state, s.mode, s.monodromy
        Py, mode_end = self(y, _copy(mode))
        return Py, mode_end, self.differences(y, mode, scale, rel_step)

    def try_derivatives(self, y, mode, dp=None, dperiod: float = 0.0):
        """:meth:`derivatives`, or None where the tangent fails and differences may stand in.

        With ``jacobian="tangent"`` a failure is not excused: it raises :class:`FlowError`.
        """
        from ..numeric.tangent import SensitivityError
        try:
            return self.derivatives(y, _copy(mode), dp, dperiod)
        except SensitivityError as e:
            if self.method == "tangent":
                raise FlowError(str(e)) from None
            return None

    def jacobian(self, y, mode, scale, rel_step: float = 1e-6) -> np.ndarray:
        """``dP/dy`` at ``(y, mode)``: the tangent of the flow, or central differences.

        With the tangent (``exact``), the derivative of the kernel's discrete flow along
        its events. Otherwise column ``i`` is a central difference with step
        ``rel_step * scale[i]``; every perturbed start keeps ``mode``, so the map is
        differentiated along the event sequence of ``(y, mode)``, which is what its
        eigenvalues describe as long as no event of the orbit is grazing (a
        perturbation of ``rel_step`` would then change the sequence).
        """
        if self.exact:
            s = self.try_derivatives(y, mode)
            if s is not None:
                return s.monodromy
        return self.differences(y, mode, scale, rel_step)

    def differences(self, y, mode, scale, rel_step: float = 1e-6) -> np.ndarray:
        """``dP/dy`` by central differences, column ``i`` with step ``rel_step * scale[i]`` (see :meth:`jacobian`)."""
        y = np.asarray(y, dtype=float)
        J = np.empty((self.n, self.n))
        for i in range(self.n):
            d = rel_step * scale[i]
            yp, ym = y.copy(), y.copy()
            yp[i] += d
            ym[i] -= d
            J[:, i] = (self(yp, _copy(mode))[0] - self(ym, _copy(mode))[0]) / (2.0 * d)
        return J


def settle(integrator, y, mode, fired: list | None = None):
    """The mode ``y`` starts in: ``mode`` with every guard already past zero at ``t = 0`` fired.

    The kernels fire a guard when it *crosses* zero within a step; a start state that
    already lies past one (a section state on the far side of a stick-slip or contact
    boundary of ``mode``) would otherwise follow ``mode``'s flow. Firing it makes the
    period map continuous across the boundary, which shooting and continuation cross
    when the orbit's switching time passes the section. The product-mode kernel only:
    the per-contact kernel's guard functions are not callable from Python, and there
    the mode is taken as given. ``y`` may be reset in place (a transition's reset);
    each transition fired is appended to ``fired`` as ``(mode, guard, target, state before)``.
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
        before = y.copy()
        target = int(mod.transition(mode, past[0], 0.0, y, integrator.p, tmp))
        if fired is not None:
            fired.append((mode, past[0], target, before))
        mode = target
    return mode


def _copy(mode):
    """A mode the kernel may update in place (the per-contact kernel's is an array)."""
    return mode.copy() if isinstance(mode, np.ndarray) else mode
