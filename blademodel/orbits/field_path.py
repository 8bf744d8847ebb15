"""How a model's raw parameters and excitation period move with one config field, without rebuilding it.

Continuation moves its field at every correction, and each value needs the
integrator's raw parameter vector and excitation period. Building them through the
config (validation, components, the model) costs several times a period's
integration of the pair. Most fields enter the parameters affinely (``omega``,
``F0``, ``gap``, ``gamma`` through ``k = gamma kx``, ``mu``), and the period either
does not move or moves as ``2 pi / omega``. :class:`AffineFieldPath` checks this on
models built at a few values across the range and then evaluates the parameters at
any value inside it by interpolation, to rounding; a field that enters any parameter
otherwise is refused (:meth:`AffineFieldPath.probe` returns ``None``) and the caller
builds each model as before.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

#: Values of the field probed across the range (ends included).
PROBES = 5
#: A parameter counts as affine in the field if every probe lies this close (relative to its
#: largest magnitude over the probes) to the line through the two ends: rounding, not curvature.
AFFINE_RTOL = 1e-12


def _affine(values: np.ndarray, x: np.ndarray) -> bool:
    """Whether ``values[k]`` (rows: probes) lie on the line through the first and last row, to rounding."""
    slope = (values[-1] - values[0]) / (x[-1] - x[0])
    line = values[0] + (x[:, None] - x[0]) * slope
    size = np.max(np.abs(values), axis=0)
    return bool(np.all(np.abs(values - line) <= AFFINE_RTOL * size))


class AffineFieldPath:
    """Raw parameters ``p(lambda)`` and excitation period ``T(lambda)`` of a config field, interpolated.

    Built by :meth:`probe`; ``p`` is affine in ``lambda`` on ``[lo, hi]``, and ``T``
    is constant, affine, or its reciprocal is (``T = 2 pi / omega``), each checked
    on models built at :data:`PROBES` values.

    Attributes
    ----------
    lo, hi : float
        The probed range; :meth:`covers` says whether a value lies in it.
    """

    def __init__(self, x, P, T, reciprocal: bool):
        self.lo, self.hi = float(x[0]), float(x[-1])
        self._x0, self._p0 = float(x[0]), P[0].copy()
        self._dp = (P[-1] - P[0]) / (x[-1] - x[0])
        self._reciprocal = reciprocal
        if T is None:
            self._T0 = self._dT = None
        else:
            q = 1.0 / T if reciprocal else T
            self._T0, self._dT = float(q[0]), float((q[-1] - q[0]) / (x[-1] - x[0]))

    @classmethod
    def probe(cls, build: Callable[[float], tuple], lo: float, hi: float) -> "AffineFieldPath | None":
        """Check the field on ``[lo, hi]`` and return its path, or ``None`` if it does not move affinely.

        Parameters
        ----------
        build : callable
            ``build(value) -> (p_raw, period)``: the raw parameter vector and the
            excitation period (``None`` when the model has none of its own) of the
            model the config builds at ``value``; may raise ``ValueError``.
        lo, hi : float
            The range, ``lo < hi``.
        """
        x = np.linspace(lo, hi, PROBES)
        try:
            built = [build(float(v)) for v in x]
        except ValueError:
            return None
        P = np.array([b[0] for b in built], dtype=float)
        if not (np.all(np.isfinite(P)) and _affine(P, x)):
            return None
        periods = [b[1] for b in built]
        if all(T is None for T in periods):
            return cls(x, P, None, False)
        if any(T is None for T in periods):
            return None
        T = np.array(periods, dtype=float)[:, None]
        for reciprocal in (False, True):
            if _affine(1.0 / T if reciprocal else T, x):
                return cls(x, P, T[:, 0], reciprocal)
        return None

    def covers(self, value: float) -> bool:
        """Whether ``value`` lies in the probed range."""
        return self.lo <= value <= self.hi

    def at(self, value: float) -> tuple[np.ndarray, float | None]:
        """``(p_raw, period)`` at ``value`` (``period`` None when the model has none of its own)."""
        d = value - self._x0
        p = self._p0 + d * self._dp
        if self._T0 is None:
            return p, None
        q = self._T0 + d * self._dT
        return p, (1.0 / q if self._reciprocal else q)

    def derivative(self, value: float) -> tuple[np.ndarray, float]:
        """``(d p_raw / d lambda, d T / d lambda)`` at ``value`` (exact for the interpolation)."""
        if self._T0 is None:
            return self._dp.copy(), 0.0
        if not self._reciprocal:
            return self._dp.copy(), self._dT
        T = self.at(value)[1]
        return self._dp.copy(), -self._dT * T * T
