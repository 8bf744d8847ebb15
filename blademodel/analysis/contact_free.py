"""The exact steady state of a model without its contacts: the reference ``P0`` of ``P_d`` along a branch.

Without contacts a model is linear, ``y' = A y + b0 + bc cos(w t) + bs sin(w t)`` (``w`` the
excitation frequency), and its steady state is ``y0 + Re(Y exp(i w t))`` with ``A y0 = -b0``
and ``(i w - A) Y = bc - i bs``: each state's time-mean square is ``y0**2 + |Y|**2 / 2``,
exactly, with no transient to integrate away (a sweep integrates the contact-free model from
rest for its ``P0``, :func:`~blademodel.numeric.mean_square.mean_square_run`).
"""

from __future__ import annotations

import numpy as np


def contact_free_mean_squares(model) -> dict:
    """Each state's time-mean square over the steady state of ``model`` without its contacts.

    Parameters
    ----------
    model : Model
        A built model with an excitation period.

    Returns
    -------
    dict
        ``{state name: mean square}`` of the contact-free model's states (coordinates and
        velocities), SI units squared.

    Raises
    ------
    ValueError
        If the contact-free model is not linear, its forcing holds other harmonics than the
        excitation's, or it has no steady state (an undamped resonance).
    """
    from ..numeric.kernels import make_integrator
    from ..numeric.mean_square import without_contacts
    ig = make_integrator(without_contacts(model), kernel="product")
    n = ig.n_physical
    zero = np.zeros(ig.n_state)
    mode = ig.mode_of(zero)
    A = ig.module.jacobian(mode, ig.p_raw)[:n, :n]
    out = np.empty(ig.n_state)

    def rhs(t, y):
        full = zero.copy()
        full[:n] = y
        ig.module.rhs(mode, float(t), full, ig.p, out)
        return out[:n].copy()

    w = 2.0 * np.pi / ig.period
    ts = ig.period * np.arange(8) / 8.0
    B = np.array([rhs(t, np.zeros(n)) for t in ts])
    M = np.column_stack([np.ones(ts.size), np.cos(w * ts), np.sin(w * ts)])
    (b0, bc, bs), *_ = np.linalg.lstsq(M, B, rcond=None)
    size = max(float(np.max(np.abs(B))), 1e-300)
    if np.max(np.abs(M @ np.array([b0, bc, bs]) - B)) > 1e-12 * size:
        raise ValueError(f"{model.name} without contacts: its forcing holds other harmonics than the excitation's "
                         f"(omega = {w:g} rad/s): no closed-form steady state for P0")
    probe = np.random.default_rng(0).uniform(-1.0, 1.0, n)
    if np.max(np.abs(rhs(0.0, probe) - B[0] - A @ probe)) > 1e-9 * max(float(np.max(np.abs(A @ probe))), 1e-300):
        raise ValueError(f"{model.name} without contacts is not linear: no closed-form steady state for P0")
    try:
        y0 = np.linalg.solve(A, -b0)
        Y = np.linalg.solve(1j * w * np.eye(n) - A, bc - 1j * bs)
    except np.linalg.LinAlgError:
        raise ValueError(f"{model.name} without contacts has no steady state at omega = {w:g} rad/s (an undamped "
                         f"resonance, or a free rigid motion)") from None
    return dict(zip(list(ig.meta["state"])[:n], map(float, y0 ** 2 + 0.5 * np.abs(Y) ** 2)))
