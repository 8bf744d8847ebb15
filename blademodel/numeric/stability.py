"""The stepping method's stability limit from the stiffest mode of a model (RK4 by default)."""

from __future__ import annotations

import math

import numpy as np


class StepTooLargeError(ValueError):
    """The requested step lies outside RK4's stability region for some mode."""


def rk4_amplification(z: np.ndarray) -> np.ndarray:
    """RK4's stability polynomial ``R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24``."""
    return 1 + z + z ** 2 / 2 + z ** 3 / 6 + z ** 4 / 24


def ray_limits(lams, amplification=rk4_amplification) -> np.ndarray:
    """Largest ``h`` with ``|R(h lam)| <= 1`` along the ray of each ``lam`` (``R``: ``amplification``).

    A bisection of 60 halvings, all rays at once (one call of ``amplification`` on an
    array per halving); ``inf`` for ``lam = 0`` and where the method's region does not
    end on the ray.
    """
    lams = np.asarray(lams, dtype=complex).ravel()
    out = np.full(lams.shape, math.inf)
    live = np.abs(lams) > 0.0
    lam = lams[live]
    lo, hi = np.zeros(lam.shape), 10.0 / np.abs(lam)  # the regions of RK4 and RK8 lie within |z| < 3 and < 7
    bounded = np.abs(amplification(hi * lam)) > 1.0  # unbounded only for Re(lam) > 0: growth is then physical
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        inside = np.abs(amplification(mid * lam)) <= 1.0 + 1e-12
        lo = np.where(inside, mid, lo)
        hi = np.where(inside, hi, mid)
    out[np.flatnonzero(live)[bounded]] = lo[bounded]
    return out


def physical_eigenvalues(J: np.ndarray) -> np.ndarray:
    """The eigenvalues of ``J`` that a stable step must keep bounded (physically growing ones left out)."""
    lam = np.linalg.eigvals(J)
    return lam[~(lam.real > 1e-9 * np.maximum(np.abs(lam), 1.0))]


def stable_step(J: np.ndarray, amplification=rk4_amplification) -> float:
    """Largest stable step for the state Jacobian ``J`` (its physically unstable modes left out)."""
    lam = physical_eigenvalues(J)
    return float(np.min(ray_limits(lam, amplification))) if lam.size else math.inf


def max_stable_step(jacobian, n_modes: int, p: np.ndarray, n_state: int,
                    amplification=rk4_amplification) -> tuple[float, int]:
    """Largest stable step over every mode, and the mode that sets it.

    Parameters
    ----------
    jacobian : callable
        ``jacobian(mode, p)``: the state Jacobian of ``mode``.
    n_modes : int
    p : ndarray
        Raw parameter vector.
    n_state : int
        Number of physical states (the Jacobian's size).
    amplification : callable
        The method's stability function (default RK4's).
    """
    lam, owner = mode_eigenvalues(jacobian, n_modes, p, n_state)
    if not lam.size:
        return math.inf, -1
    limits = ray_limits(lam, amplification)   # every mode's rays in one bisection
    i = int(np.argmin(limits))
    return (float(limits[i]), int(owner[i])) if math.isfinite(limits[i]) else (math.inf, -1)


def mode_eigenvalues(jacobian, n_modes: int, p: np.ndarray, n_state: int) -> tuple[np.ndarray, np.ndarray]:
    """The :func:`physical_eigenvalues` of every mode's Jacobian, and the mode each belongs to."""
    lams = [physical_eigenvalues(jacobian(mode, p)[:n_state, :n_state]) for mode in range(n_modes)]
    owner = [np.full(lam.size, mode) for mode, lam in enumerate(lams)]
    return np.concatenate(lams or [np.zeros(0)]), np.concatenate(owner or [np.zeros(0, dtype=int)])


def certain_step(lam, coefficients) -> float:
    """The largest ``h`` such that every step in ``[0, h]`` is stable for all the eigenvalues ``lam``.

    Along the ray of an eigenvalue ``lam``, ``|R(r lam)|^2 - 1`` is a real polynomial in
    ``r`` (``R(z) = sum_k c_k z^k``, ``coefficients`` lowest first); at most its first
    positive root the step is stable, whatever the shape of the method's region
    further out. ``inf`` where no ray leaves the region (``lam = 0``, or none given).
    Exact up to the roots' rounding; a step above it is not necessarily unstable
    (:func:`step_is_stable` decides those).
    """
    c = np.asarray(coefficients, dtype=float)
    out = np.inf
    for l in np.atleast_1d(np.asarray(lam, dtype=complex)):
        if l == 0:
            continue
        a = c * l ** np.arange(c.size)              # R(r l) = sum_k a_k r^k
        f = np.convolve(a, np.conj(a)).real          # |R(r l)|^2
        f[0] -= 1.0
        hi_first = f[::-1]
        r = np.roots(hi_first)
        pos = r.real[(np.abs(r.imag) <= 1e-9 * np.abs(r)) & (r.real > 0)]
        if pos.size:
            x = float(pos.min())
            d = np.polyder(hi_first)
            for _ in range(3):   # Newton polishes the root (np.roots leaves ~1e-6 on RK8's degree 24)
                slope = np.polyval(d, x)
                if slope != 0.0:
                    x -= np.polyval(hi_first, x) / slope
            out = min(out, x)
    return out


def step_is_stable(h: float, lam: np.ndarray, amplification=rk4_amplification) -> bool:
    """Whether ``|R(h lam)| <= 1`` for the eigenvalues ``lam`` (:func:`mode_eigenvalues`): one evaluation, no limit sought."""
    return bool(np.all(np.abs(amplification(h * np.asarray(lam))) <= 1.0 + 1e-12))


def check_step(period: float, steps_per_period: int, h_max: float, mode_name: str, method: str = "rk4") -> None:
    """Raise :class:`StepTooLargeError` if ``period / steps_per_period > h_max``."""
    h = period / steps_per_period
    if h > h_max:
        need = math.ceil(period / h_max)
        raise StepTooLargeError(
            f"steps_per_period = {steps_per_period} gives h = {h:.3e} s, above {method.upper()}'s stability "
            f"limit {h_max:.3e} s set by mode '{mode_name}'; use steps_per_period >= {need}")
