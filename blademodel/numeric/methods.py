"""The explicit Runge-Kutta methods a kernel steps with.

Both kernels step with classical RK4 by default (fused in the product-mode kernel).
``method="rk8"`` takes an eighth-order method through the same event machinery:
every trial of an event's location is a sub-step of the method itself, so events
keep its order. It pays where accuracy is high: twelve stages a step instead of
four, but the error falls as ``h^8`` instead of ``h^4``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Method:
    """An explicit Runge-Kutta method: Butcher tableau ``A`` (strictly lower), weights ``b``, nodes ``c``.

    Parameters
    ----------
    name : str
    order : int
        Classical order.
    A, b, c : ndarray
    """

    name: str
    order: int
    A: np.ndarray
    b: np.ndarray
    c: np.ndarray
    _highest_first: np.ndarray = field(init=False, repr=False, compare=False)

    @property
    def stages(self) -> int:
        """Number of stages (right-hand-side evaluations a step)."""
        return len(self.b)

    def __post_init__(self):
        c = [1.0]
        v = np.ones(self.stages)
        for _ in range(self.stages):
            c.append(float(self.b @ v))
            v = self.A @ v
        object.__setattr__(self, "_highest_first", np.array(c[::-1]))

    def amplification(self, z):
        """Stability function ``R(z) = 1 + sum_k (b^T A^(k-1) 1) z^k`` (a polynomial: the method is explicit)."""
        return np.polyval(self._highest_first, np.asarray(z, dtype=complex))

    def amplification_coefficients(self) -> np.ndarray:
        """The coefficients of :meth:`amplification`, lowest power first (``1, 1, 1/2, ...``)."""
        return self._highest_first[::-1].copy()

    def tableau(self) -> np.ndarray:
        """``A`` (row by row), ``b`` and ``c`` in one flat array, as the kernels read them."""
        return np.concatenate([self.A.ravel(), self.b, self.c]).astype(float)


def _rk4() -> Method:
    A = np.zeros((4, 4))
    A[1, 0] = A[2, 1] = 0.5
    A[3, 2] = 1.0
    return Method("rk4", 4, A, np.array([1, 2, 2, 1]) / 6.0, np.array([0.0, 0.5, 0.5, 1.0]))


def _rk8() -> Method:
    """The eighth-order solution of Dormand and Prince's 8(5,3) pair (twelve stages).

    The coefficients are those published by Hairer, Norsett and Wanner (*Solving
    Ordinary Differential Equations I*, 2nd ed., section II.10), as SciPy's DOP853
    carries them; only the propagating eighth-order solution is used (fixed step, no
    error estimate). ``tests/test_methods.py`` checks the order conditions.
    """
    from scipy.integrate._ivp import dop853_coefficients as dop
    s = dop.N_STAGES
    return Method("rk8", 8, np.array(dop.A[:s, :s], dtype=float), np.array(dop.B, dtype=float),
                  np.array(dop.C[:s], dtype=float))


#: The methods by name.
METHOD_NAMES = ("rk4", "rk8")


def get_method(name: str) -> Method:
    """The method called ``name``; ``ValueError`` naming it otherwise."""
    if name == "rk4":
        return _rk4()
    if name == "rk8":
        return _rk8()
    raise ValueError(f"method = {name!r} must be one of {', '.join(METHOD_NAMES)}")
