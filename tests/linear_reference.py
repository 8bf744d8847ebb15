"""The exact steady state of a model's contact-free (open) mode, for checking orbits and FRFs."""

import numpy as np


def linear_parts(ig):
    """``A`` and the forcing ``b_c cos(w t) + b_s sin(w t)`` of the open mode of a product-kernel integrator."""
    n, mode = ig.n_physical, ig.mode_of(np.zeros(ig.n_state))
    A = ig.module.jacobian(mode, ig.p_raw)[:n, :n]
    out = np.empty(ig.n_state)
    ig.module.rhs(mode, 0.0, np.zeros(ig.n_state), ig.p, out)
    b_c = out[:n].copy()
    ig.module.rhs(mode, ig.period / 4, np.zeros(ig.n_state), ig.p, out)
    return A, b_c, out[:n].copy()


def forced_response(ig):
    """``Y`` with the steady state ``Re(Y exp(i w t))``: ``(i w - A) Y = b_c - i b_s`` (``w = 2 pi / T``)."""
    A, b_c, b_s = linear_parts(ig)
    w = 2 * np.pi / ig.period
    return np.linalg.solve(1j * w * np.eye(A.shape[0]) - A, b_c - 1j * b_s)
