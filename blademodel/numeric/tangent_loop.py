"""Tangent integration of the hybrid flow along a recorded event sequence (template).

This file is a *template*, like :mod:`.loop`: it is pasted into a model's
sensitivity module after the generated ``rhs``, ``transition`` (:mod:`.codegen`),
``flow_jacobian``, ``guard_gradient`` and ``reset_jacobian``
(:mod:`.sensitivity_codegen`), and compiled with Numba.

:func:`replay_tangent` repeats a run of the product-mode kernel from the kernel's
event log: the same steps, each event at its logged time, the same transitions.
Along the way it carries the tangent ``V = d y / d (y0, lambda)`` of the physical
states and ``tau = d t / d (y0, lambda)`` of the current time. It differentiates
the kernel's *discrete* map exactly, not the flow it approximates:

* a (sub)step ``y_b = Phi(t_a, y_a, t_b - t_a)`` of the Runge-Kutta method is
  differentiated stage by stage in its start state, start time and length::

      dy_b = Phi_y dy_a + Phi_t0 dt_a + Phi_h (dt_b - dt_a)   (+ Phi_p dlambda)

* a step ends on the grid (``dt_b = t_b / T dT``, zero unless the period moves
  with ``lambda``) or at an event, whose time follows from its guard,
  ``g(t_b, y_b) = 0``::

      dt_b = -(g_y (dy_b with dt_b = 0) + g_p dlambda) / (g_t + g_y Phi_h)

* the transition's reset ``y+ = R(t_b, y_b)`` then gives
  ``dy+ = R_y dy_b + R_t dt_b + R_p dlambda``.

Together the event's two sub-steps and the reset make the discrete form of the
**saltation matrix** ``R_y + (f+ - R_y f-) g_y / (g_t + g_y f-)``, to which they
tend as the step shrinks. Further transitions the kernel takes at the same time (a
guard already past zero there) are resets at that fixed time: ``dt`` is kept.

The last column of ``V`` is the derivative along the parameter direction ``dp`` (a
vector over the raw parameters; ``use_p`` false: none).
"""

import math  # noqa: F401  (used by the generated code)

import numpy as np

from blademodel.numeric.contract import STATUS_GRAZING_EVENT, STATUS_NONFINITE, STATUS_OK, STATUS_REPLAY_MISMATCH


def tangent_step(mode, t, y, h, p, tab, V, use_p, dp, K, Y, dK, dY, Jy, Jp, Jt, out_y, out_V, affine, JyA, fp):
    """One step ``h`` of the tableau ``tab`` from ``(t, y)`` in ``mode`` and its derivatives.

    ``out_y`` is the step's state. ``out_V`` has ``m + 2`` columns for the ``m`` of
    ``V``: ``Phi_y V`` (plus ``Phi_p dp`` in column ``m - 1`` with ``use_p``), then
    ``Phi_t0`` and ``Phi_h``, the derivatives in the start time and the length. Each
    stage ``k_i = f(t + c_i h, Y_i)``, ``Y_i = y + h sum_j a_ij k_j`` is
    differentiated with the mode's Jacobians. With ``affine`` (the mode's flow is
    affine in the state, ``FLOW_AFFINE``) ``df/dy`` is the constant ``JyA`` and only
    ``(df/dp) dp`` and ``df/dt`` are evaluated at the stages (``fp``, ``Jt``).
    """
    s = K.shape[0]
    n = V.shape[0]
    m = V.shape[1]
    mm = m + 2
    npar = Jp.shape[1]
    for st in range(s):
        tangent_sum(y, V, h, tab, st * s, st, K, dK, Y, dY)
        ct = tab[s * s + s + st]
        tc = t + ct * h
        rhs(mode, tc, Y, p, K[st])  # noqa: F821
        if affine:
            J = JyA
            flow_partials(mode, tc, Y, p, dp, fp, Jt)  # noqa: F821
        else:
            J = Jy
            for i in range(n):
                for k in range(n):
                    Jy[i, k] = 0.0
                for j in range(npar):
                    Jp[i, j] = 0.0
                Jt[i] = 0.0
            flow_jacobian(mode, tc, Y, p, Jy, Jp, Jt)  # noqa: F821
        for i in range(n):
            for c in range(mm):
                dK[st, i, c] = 0.0
            for k in range(n):
                jik = J[i, k]
                if jik != 0.0:   # mechanical Jacobians are sparse: dx/dt = v alone fills a row with one entry
                    for c in range(mm):
                        dK[st, i, c] += jik * dY[k, c]
            if use_p:
                if affine:
                    acc = fp[i]
                else:
                    acc = 0.0
                    for j in range(npar):
                        acc += Jp[i, j] * dp[j]
                dK[st, i, m - 1] += acc
            dK[st, i, m] += Jt[i]
            dK[st, i, m + 1] += ct * Jt[i]
    tangent_sum(y, V, h, tab, s * s, s, K, dK, out_y, out_V)


def power_apply(powers, built, mode, k, V, W):
    """``V = M^k V`` for the whole-step Jacobian ``M = powers[mode, 0]`` of an affine mode, ``k >= 0``.

    A run of ``k`` whole steps of a mode whose flow is affine in the state has the
    same step Jacobian ``M`` every step: its tangent is the product of the powers
    ``M^(2^i)`` for the bits of ``k``, kept in ``powers[mode, i]`` once built
    (``built[mode]`` of them): a run costs as many products with ``V`` as ``k`` has
    bits, instead of ``k`` differentiated steps.
    """
    n = V.shape[0]
    m = V.shape[1]
    i = 0
    while k > 0:
        while built[mode] <= i:   # the next power: the square of the last
            b = built[mode]
            for r in range(n):
                for c in range(n):
                    acc = 0.0
                    for l in range(n):
                        acc += powers[mode, b - 1, r, l] * powers[mode, b - 1, l, c]
                    powers[mode, b, r, c] = acc
            built[mode] = b + 1
        if k & 1:
            for r in range(n):
                for c in range(m):
                    acc = 0.0
                    for l in range(n):
                        acc += powers[mode, i, r, l] * V[l, c]
                    W[r, c] = acc
            for r in range(n):
                for c in range(m):
                    V[r, c] = W[r, c]
        k >>= 1
        i += 1


def tangent_sum(y, V, h, tab, o, count, K, dK, out_y, out_V):
    """``out_y = y + h sum_q w_q k_q`` (``w_q = tab[o + q]``, ``q < count``) and its derivatives.

    ``out_V``'s first ``m`` columns are ``V + h sum_q w_q dk_q``, the next one (the start
    time's) ``h sum_q w_q dk_q`` and the last (the length's) ``sum_q w_q k_q + h sum_q w_q dk_q``.
    """
    N = y.shape[0]
    n = V.shape[0]
    m = V.shape[1]
    for i in range(N):
        out_y[i] = y[i]
    for i in range(n):
        for c in range(m):
            out_V[i, c] = V[i, c]
        out_V[i, m] = 0.0
        out_V[i, m + 1] = 0.0
    for q in range(count):
        wq = tab[o + q]
        if wq != 0.0:
            w = h * wq
            for i in range(N):
                out_y[i] += w * K[q, i]
            for i in range(n):
                for c in range(m + 2):
                    out_V[i, c] += w * dK[q, i, c]
                out_V[i, m + 1] += wq * K[q, i]


def queue_whole_steps(mode, k, pending, pend_mode, t, y, h, p, tab, ident, dp, K, Y, dK, dY, Jy, Jp, Jt, y1, V1, JyA,
                      fp, M, have_M, Vs, WP):
    """Queue ``k`` whole steps of the affine ``mode`` for the state columns ``Vs``, applied as ``M^k`` when the
    run ends: builds the mode's ``M`` on first use (one differentiated step from the identity) and applies
    a pending run of another mode first. Returns the new ``(pending, pend_mode)``."""
    n = Vs.shape[0]
    if have_M[mode] == 0:
        tangent_step(mode, t, y, h, p, tab, ident, False, dp, K, Y, dK, dY, Jy, Jp, Jt, y1, V1, True, JyA[mode], fp)
        for i in range(n):
            for c in range(n):
                M[mode, 0, i, c] = V1[i, c]
        have_M[mode] = 1
    if pending > 0 and pend_mode != mode:
        power_apply(M, have_M, pend_mode, pending, Vs, WP)
        pending = 0
    return pending + k, mode


def step_tangent(out_V, dt_a, dt_b, V):
    """``V = Phi_y V + Phi_t0 dt_a + Phi_h (dt_b - dt_a)`` from :func:`tangent_step`'s ``out_V``."""
    n = V.shape[0]
    m = V.shape[1]
    for i in range(n):
        for c in range(m):
            V[i, c] = out_V[i, c] + out_V[i, m] * dt_a[c] + out_V[i, m + 1] * (dt_b[c] - dt_a[c])


def event_time_tangent(mode, gi, t, y, p, out_V, dt_a, V, use_p, dp, gy, gp, dt_b):
    """``dt_b`` of an event of guard ``gi`` at the end of the sub-step ``out_V``, and ``V`` there.

    Returns False if the guard's rate along the sub-step is zero (grazing).
    """
    n = V.shape[0]
    m = V.shape[1]
    npar = gp.shape[0]
    for k in range(n):
        gy[k] = 0.0
    for j in range(npar):
        gp[j] = 0.0
    gt = guard_gradient(mode, gi, t, y, p, gy, gp)  # noqa: F821
    rate = gt
    for k in range(n):
        rate += gy[k] * out_V[k, m + 1]
    if rate == 0.0 or not math.isfinite(rate):
        return False
    for c in range(m):   # V with the end time held (absolute) first
        dt_b[c] = 0.0
    step_tangent(out_V, dt_a, dt_b, V)
    for c in range(m):
        r = 0.0
        for k in range(n):
            r += gy[k] * V[k, c]
        if use_p and c == m - 1:
            for j in range(npar):
                r += gp[j] * dp[j]
        dt_b[c] = -r / rate
    for i in range(n):
        for c in range(m):
            V[i, c] += out_V[i, m + 1] * dt_b[c]
    return True


def reset_tangent(mode, gi, target, t, y, p, V, dt, use_p, dp, Ry, Rp, Rt, ytmp, W):
    """Apply the transition of guard ``gi`` of ``mode`` to ``target`` to ``y``, and its reset's derivative to ``V``.

    Returns the new mode, or ``-STATUS_REPLAY_MISMATCH``.
    """
    n = V.shape[0]
    m = V.shape[1]
    npar = Rp.shape[1]
    for i in range(n):
        for k in range(n):
            Ry[i, k] = 1.0 if i == k else 0.0
        for j in range(npar):
            Rp[i, j] = 0.0
        Rt[i] = 0.0
    if not reset_jacobian(mode, gi, target, t, y, p, Ry, Rp, Rt):  # noqa: F821
        return -STATUS_REPLAY_MISMATCH
    new_mode = transition(mode, gi, t, y, p, ytmp)  # noqa: F821
    if new_mode != target:
        return -STATUS_REPLAY_MISMATCH
    for i in range(n):
        for c in range(m):
            acc = Rt[i] * dt[c]
            for k in range(n):
                acc += Ry[i, k] * V[k, c]
            if use_p and c == m - 1:
                for j in range(npar):
                    acc += Rp[i, j] * dp[j]
            W[i, c] = acc
    for i in range(n):
        for c in range(m):
            V[i, c] = W[i, c]
    return new_mode


def skip_to(te, g, n_steps, period, start_period, steps_per_period, h):
    """The first step from ``g`` whose end is at or after ``te``: the step that holds an event at ``te``."""
    k = max(g, int((te - period * start_period) / h) - 2)
    while k < n_steps:
        per = start_period + k // steps_per_period
        if period * per + (k - (per - start_period) * steps_per_period + 1) * h >= te:
            return k
        k += 1
    return n_steps


def kernel_step(mode, t, y, h, p, ktab, k1, k2, k3, k4, tmp, y1, KK):
    """Step ``y`` in place exactly as the kernel does: its fused RK4 (``ktab`` empty) or its tableau."""
    if ktab.shape[0] == 0:
        rk4_step(mode, t, y, h, p, k1, k2, k3, k4, tmp, y1)  # noqa: F821
    else:
        rk_step(mode, t, y, h, p, k1, k2, k3, k4, tmp, y1, ktab, KK)  # noqa: F821
    for i in range(y.shape[0]):
        y[i] = y1[i]


def same_state(y, rec_y, k):
    """Whether the replay's state ``y`` is the kernel's recorded row ``k`` (to ``1e-9`` of the row's size), made equal."""
    N = y.shape[0]
    size = 0.0
    for i in range(N):
        size = max(size, abs(rec_y[k, i]))
    for i in range(N):
        if abs(y[i] - rec_y[k, i]) > 1e-9 * (abs(rec_y[k, i]) + size):
            return False
        y[i] = rec_y[k, i]
    return True


def affine_jacobian(mode, t, y, p, Jy, Jp, Jt, JyA, known):
    """Whether ``mode``'s flow is affine in the state; if so its constant ``df/dy`` is in ``JyA[mode]`` (built once)."""
    if FLOW_AFFINE[mode] == 0:  # noqa: F821
        return False
    if known[mode] == 0:
        n = Jy.shape[0]
        for i in range(n):
            for k in range(n):
                Jy[i, k] = 0.0
            for j in range(Jp.shape[1]):
                Jp[i, j] = 0.0
            Jt[i] = 0.0
        flow_jacobian(mode, t, y, p, Jy, Jp, Jt)  # noqa: F821
        for i in range(n):
            for k in range(n):
                JyA[mode, i, k] = Jy[i, k]
        known[mode] = 1
    return True


def replay_tangent(y, mode, p, period, steps_per_period, start_period, end_period, tab, ktab, log_t, log_guard,
                   log_from, log_to, n_log, V, use_p, dp, dperiod, rec_y):
    """Repeat the kernel's run over periods ``start_period .. end_period`` from its log, carrying ``V``.

    ``y`` (the full state) and ``V`` (physical states by columns) are updated in
    place. The step grid is the kernel's (``h = period / steps_per_period``); inside
    a step, the sub-steps end at the logged event times, where the logged
    transitions are taken. ``dperiod`` is the period's derivative along ``dp``: the
    grid times move with it. ``tab`` is the method's tableau for the tangent; the state
    itself is stepped as the kernel steps it (``ktab``: empty for the fused RK4), so that
    it follows the kernel's rounding and a reset that decides on a guard's sign right at
    its root (which of an Iwan law's elements slip) decides as the kernel did.

    A whole step without events in a mode whose flow is affine in the state
    (``FLOW_AFFINE``) has the same Jacobian ``M = Phi_y`` every time (the method's
    stability polynomial of ``h df/dy``): the state columns of ``V`` are multiplied by
    ``M^k`` once a run of ``k`` such steps ends (:func:`power_apply`), and only the
    parameter column, whose steps depend on the state and the time, is carried step by
    step. ``rec_y``, if it has rows (the kernel's run recorded at every step from
    ``start_period``, its start in row 0), saves stepping the state through those
    whole steps: it is read from the record, and wherever the replay's own state
    reaches the grid after events it must equal the record's (else
    ``STATUS_REPLAY_MISMATCH``: a reset that decided otherwise than the kernel's).
    Returns ``(status, mode, t)``.
    """
    N = y.shape[0]
    n = V.shape[0]
    m = V.shape[1]
    npar = dp.shape[0]
    s = int(round(math.sqrt(tab.shape[0] + 1.0))) - 1
    K = np.empty((s, N))
    Y = np.empty(N)
    dK = np.empty((s, n, max(m, n) + 2))
    dY = np.empty((n, max(m, n) + 2))
    Jy = np.empty((n, n))
    Jp = np.empty((n, npar))
    Jt = np.empty(n)
    fp = np.empty(n)
    y1 = np.empty(N)
    V1 = np.empty((n, max(m, n) + 2))
    gy = np.empty(n)
    gp = np.empty(npar)
    Ry = np.empty((n, n))
    Rp = np.empty((n, npar))
    Rt = np.empty(n)
    ytmp = np.empty(N)
    W = np.empty((n, m))
    k1 = np.empty(N)
    k2 = np.empty(N)
    k3 = np.empty(N)
    k4 = np.empty(N)
    tmp = np.empty(N)
    sk = int(round(math.sqrt(ktab.shape[0] + 1.0))) - 1 if ktab.shape[0] > 0 else 0
    KK = np.empty((sk, N))
    n_modes = FLOW_AFFINE.shape[0]  # noqa: F821
    JyA = np.zeros((n_modes, n, n))
    known = np.zeros(n_modes, dtype=np.int64)
    # an affine mode's whole-step Jacobian M and its powers M^(2^i), as built (have_M of them)
    max_bits = 1
    while (1 << max_bits) <= steps_per_period * (end_period - start_period):
        max_bits += 1
    M = np.empty((n_modes, max_bits, n, n))
    have_M = np.zeros(n_modes, dtype=np.int64)
    ident = np.zeros((n, n))
    for i in range(n):
        ident[i, i] = 1.0
    WP = np.empty((n, m))
    ns = m - 1 if use_p else m   # the state columns (the start state's directions)
    Vs = V[:, :ns]
    Vp = V[:, ns:]               # the parameter column (empty without use_p)
    dt = np.zeros(m)      # d t / d (y0, lambda) of the current time
    dt_b = np.zeros(m)
    dtp = dt[ns:]
    dtp_b = dt_b[ns:]
    pending = 0           # whole steps of mode ``pend_mode`` not yet applied to the state columns
    pend_mode = -1
    h = period / steps_per_period
    t = period * start_period
    if use_p:
        dt[m - 1] = t / period * dperiod
    ie = 0
    have_rec = rec_y.shape[0] > 0
    n_steps = steps_per_period * (end_period - start_period)
    g = 0
    while g < n_steps:
        per = start_period + g // steps_per_period
        j = g - (per - start_period) * steps_per_period
        t_end = period * per + (j + 1) * h
        kg = g + 1   # the record's row at t_end
        if have_rec and not use_p and (ie >= n_log or log_t[ie] > t_end) and \
                affine_jacobian(mode, t, y, p, Jy, Jp, Jt, JyA, known):
            # whole steps up to the one that holds the next event: their Jacobian is M^k, their end
            # state the record's
            g_ev = n_steps if ie >= n_log else skip_to(log_t[ie], g, n_steps, period, start_period,
                                                       steps_per_period, h)
            pending, pend_mode = queue_whole_steps(mode, g_ev - g, pending, pend_mode, t, y, h, p, tab, ident, dp, K,
                                                   Y, dK, dY, Jy, Jp, Jt, y1, V1, JyA, fp, M, have_M, Vs, WP)
            for i in range(N):
                y[i] = rec_y[g_ev, i]
            per = start_period + (g_ev - 1) // steps_per_period
            t = period * per + (g_ev - (per - start_period) * steps_per_period) * h
            g = g_ev
            continue
        g += 1
        whole = True
        while True:
            event = ie < n_log and log_t[ie] <= t_end
            te = log_t[ie] if event else t_end
            aff = affine_jacobian(mode, t, y, p, Jy, Jp, Jt, JyA, known)
            if whole and not event and te > t and aff:
                pending, pend_mode = queue_whole_steps(mode, 1, pending, pend_mode, t, y, h, p, tab, ident, dp, K, Y,
                                                       dK, dY, Jy, Jp, Jt, y1, V1, JyA, fp, M, have_M, Vs, WP)
                if use_p:
                    tangent_step(mode, t, y, te - t, p, tab, Vp, True, dp, K, Y, dK, dY, Jy, Jp, Jt, y1, V1, True,
                                 JyA[mode], fp)
                    dtp_b[0] = t_end / period * dperiod
                    step_tangent(V1, dtp, dtp_b, Vp)
                    dtp[0] = dtp_b[0]
                if have_rec and kg < rec_y.shape[0]:
                    for i in range(N):
                        y[i] = rec_y[kg, i]
                else:
                    kernel_step(mode, t, y, te - t, p, ktab, k1, k2, k3, k4, tmp, y1, KK)
                t = t_end
                break
            whole = False
            if pending > 0:
                power_apply(M, have_M, pend_mode, pending, Vs, WP)
                pending = 0
            if te > t:
                tangent_step(mode, t, y, te - t, p, tab, V, use_p, dp, K, Y, dK, dY, Jy, Jp, Jt, y1, V1, aff,
                             JyA[mode], fp)
                kernel_step(mode, t, y, te - t, p, ktab, k1, k2, k3, k4, tmp, y1, KK)
                if event:
                    if not event_time_tangent(mode, log_guard[ie], te, y, p, V1, dt, V, use_p, dp, gy, gp,
                                              dt_b):
                        return STATUS_GRAZING_EVENT, mode, te
                else:
                    for c in range(m):
                        dt_b[c] = 0.0
                    if use_p:
                        dt_b[m - 1] = t_end / period * dperiod
                    step_tangent(V1, dt, dt_b, V)
                for c in range(m):
                    dt[c] = dt_b[c]
                t = te
            elif not event:
                # an event right at the step's end: its time was the guard's, the grid
                # time is fixed; the state moves by f over the (zero) difference
                rhs(mode, t, y, p, K[0])  # noqa: F821
                for c in range(m):
                    dt_b[c] = 0.0
                if use_p:
                    dt_b[m - 1] = t_end / period * dperiod
                for i in range(n):
                    for c in range(m):
                        V[i, c] += K[0, i] * (dt_b[c] - dt[c])
                for c in range(m):
                    dt[c] = dt_b[c]
            if not event:
                t = t_end
                if have_rec and kg < rec_y.shape[0] and not same_state(y, rec_y, kg):
                    return STATUS_REPLAY_MISMATCH, mode, t
                break
            while ie < n_log and log_t[ie] == te:
                if log_from[ie] != mode:
                    return STATUS_REPLAY_MISMATCH, mode, t
                new_mode = reset_tangent(mode, log_guard[ie], log_to[ie], t, y, p, V, dt, use_p, dp, Ry, Rp,
                                         Rt, ytmp, W)
                if new_mode < 0:
                    return -new_mode, mode, t
                mode = new_mode
                ie += 1
        for i in range(N):
            if not math.isfinite(y[i]):
                return STATUS_NONFINITE, mode, t
    if pending > 0:
        power_apply(M, have_M, pend_mode, pending, Vs, WP)
    return STATUS_OK, mode, t
