"""An independent event-driven reference for linear structures with Coulomb contacts.

Used by ``tests/test_coupled_contacts.py`` to check the per-contact kernel
(``blademodel.numeric.contact_loop``). Nothing here imports ``blademodel``'s numeric
code: the structure is a set of plain NumPy matrices, the smooth arcs are
integrated by :func:`scipy.integrate.solve_ivp` (DOP853, tight tolerances) and the
events are located by SciPy's own root finder; the friction problem at an event is
solved by brute-force **enumeration** of every stick/slip assignment, not by
pivoting.

System (``n`` coordinates, ``nc`` contacts)::

    M q'' + C q' + K q = F(t) - Gn^T N - Gr^T f,     F(t) = fs sin(w t) + fc cos(w t)

``Gn[j]`` is the gradient of contact ``j``'s penetration ``delta_j = Gn[j] q - gap_j``
and ``Gr[j]`` that of its relative slip, so ``v_j = Gr[j] q'``. ``N_j = k_j delta_j``
while the contact is closed (it closes when ``delta_j`` rises through zero and opens
when it falls through zero). The friction force ``f_j`` of a closed contact obeys
Coulomb's law with coefficient ``mu_j``:

* ``slip+`` / ``slip-``: ``f_j = s mu_j N_j`` (``s = +1 / -1``);
* ``stick``: ``v_j`` is held at zero; the stick forces of all sticking contacts
  ``S`` are solved jointly from zero relative tangential acceleration,
  ``(Gr_S M^-1 Gr_S^T) f_S = Gr_S M^-1 F_known``.

Modes are numbered as in the kernel: ``0`` open, ``1`` stick, ``2`` slip+,
``3`` slip-.

Events (``solve_ivp`` terminal event functions of the current modes): ``delta_j``
rising through zero (an open contact closes: it slips along ``v_j``, or joins the
friction problem if ``v_j`` is zero), ``delta_j`` falling through zero (it opens),
``s v_j`` falling through zero for a slipping contact, ``mu_j N_j -+ f_j`` falling
through zero for a sticking one. Every guard of the old modes that is past zero at
the event (simultaneous events) fires too. The state is taken strictly past the
located root (the first ``t_e + d``, ``d`` = 0, 1 ulp, doubling, on the dense
output, at which the reported guard is strictly past zero), like the kernel, which
keeps the far end of its bisection bracket. A guard whose root coincides with the
reported one may lie a rounding error short of zero there; it fires too if it is
within ``simultaneity_tol`` of zero relative to the magnitude of its terms.

Friction problem (at every event and at the start): the closed contacts that are
sticking, that fired a ``v = 0`` or stick guard, or whose ``|v|`` is at most
``v_tol``, are *undetermined*. Every assignment of ``{stick, slip+, slip-}`` to
them is tried: the velocities are projected onto the stick constraints if the
assignment makes a contact stick that did not stick before the event
(``u -= M^-1 G_S^T (G_S M^-1 G_S^T)^-1 G_S u``); it is *consistent* if every
sticking contact has ``|f| <= mu N`` and every slipping contact ``s`` has
``s a >= 0`` (``a`` its relative tangential acceleration), up to ``cone_tol``
(relative to ``mu N`` and to ``W_jj mu N``). Exactly one consistent assignment is
expected (the Delassus matrix of an open chain is positive definite); several are
accepted only when they give the same friction forces to ``tie_tol`` (a tie at
round-off on a cone boundary), and the least violating one is taken. Otherwise
:class:`FrictionProblemError` is raised, so a test using the reference fails.

Implementation: for fixed modes every quantity (``N``, ``f``, the accelerations, the
guards) is affine in ``X = (q, u, 1, F(t))``. :meth:`CoulombReference._linear` is the
plain computation above; applied once per mode combination to the columns of the
identity it gives those affine maps, which the flow, the event functions and the
enumeration all use (one arithmetic for all three, and a fast right-hand side).

Builders: :func:`row_chain` writes the matrices of a row of 2-DOF blades by hand
from the parameters of ``models/blade_row_3.yaml`` (the conventions of
``blademodel/components/contact.py``: ``r = x cos a + y sin a``,
``n = x sin a - y cos a``, ``delta = n1 - n2 - gap``); :func:`chain_from_tables`
reads the same matrices from the kernel's ``NumericTables`` (only ``M``, ``K``,
``C``, the forcing and the contact geometry; nothing of the kernel's dynamics),
and the tests check that both agree.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

OPEN, STICK, SLIP_P, SLIP_M = 0, 1, 2, 3
MODE_NAMES = ("open", "stick", "slip+", "slip-")
CLOSED_MODES = (STICK, SLIP_P, SLIP_M)


def slip_sign(mode: int) -> float:
    return 1.0 if mode == SLIP_P else -1.0


class FrictionProblemError(AssertionError):
    """No consistent stick/slip assignment, or several with different forces."""


@dataclass
class ContactChain:
    """Plain matrices of a linear structure with gapped Coulomb contacts.

    Attributes
    ----------
    m : (n,) masses (``M`` is diagonal); K, C : (n, n)
    fs, fc : (n,) forcing ``F(t) = fs sin(omega t) + fc cos(omega t)``; omega : float
    Gn, Gr : (nc, n) gradients of each contact's penetration and relative slip
    gap, k, mu : (nc,) gap (penetration ``Gn q - gap``), normal stiffness, friction coefficient
    """

    m: np.ndarray
    K: np.ndarray
    C: np.ndarray
    fs: np.ndarray
    fc: np.ndarray
    omega: float
    Gn: np.ndarray
    Gr: np.ndarray
    gap: np.ndarray
    k: np.ndarray
    mu: np.ndarray

    @property
    def n(self) -> int:
        return self.m.shape[0]

    @property
    def nc(self) -> int:
        return self.Gn.shape[0]

    @property
    def period(self) -> float:
        return 2.0 * math.pi / self.omega

    def load(self, t: float) -> np.ndarray:
        return self.fs * math.sin(self.omega * t) + self.fc * math.cos(self.omega * t)

    @property
    def W(self) -> np.ndarray:
        """Delassus matrix ``Gr M^-1 Gr^T``."""
        return (self.Gr / self.m) @ self.Gr.T


def row_chain(p: dict, n_blades: int = 3) -> ContactChain:
    """The row of ``n_blades`` 2-DOF blades of ``models/blade_row_3.yaml``, written by hand.

    Coordinates ``x1, y1, x2, y2, ...``; blade ``i`` has springs ``kx``, ``ky`` and
    dampers ``cx``, ``cy`` to ground, the load ``F0 sin(omega t + phi_i)`` along the
    angle ``beta``, and contact ``j`` joins blades ``j`` and ``j + 1`` (gap ``Delta``,
    angle ``alpha``, stiffness ``k``, friction ``mu``).
    """
    n = 2 * n_blades
    m = np.full(n, float(p["m"]))
    K = np.diag([p["kx"], p["ky"]] * n_blades).astype(float)
    C = np.diag([p["cx"], p["cy"]] * n_blades).astype(float)
    fs, fc = np.zeros(n), np.zeros(n)
    cb, sb = math.cos(p["beta"]), math.sin(p["beta"])
    for i in range(n_blades):
        phi = p[f"phi{i + 1}"]
        fs[2 * i:2 * i + 2] = p["F0"] * math.cos(phi) * np.array([cb, sb])
        fc[2 * i:2 * i + 2] = p["F0"] * math.sin(phi) * np.array([cb, sb])
    nc = n_blades - 1
    Gn, Gr = np.zeros((nc, n)), np.zeros((nc, n))
    sa, ca = math.sin(p["alpha"]), math.cos(p["alpha"])
    for j in range(nc):
        a, b = 2 * j, 2 * j + 2  # x of body 1 and of body 2
        Gn[j, a:a + 2] = [sa, -ca]     # n1 = x1 sin a - y1 cos a
        Gn[j, b:b + 2] = [-sa, ca]     # - n2
        Gr[j, a:a + 2] = [ca, sa]      # r1 = x1 cos a + y1 sin a
        Gr[j, b:b + 2] = [-ca, -sa]    # - r2
    return ContactChain(m, K, C, fs, fc, float(p["omega"]), Gn, Gr, np.full(nc, float(p["Delta"])),
                        np.full(nc, float(p["k"])), np.full(nc, float(p["mu"])))


def chain_from_tables(tables, mu) -> ContactChain:
    """The same matrices read from a kernel's ``NumericTables`` (structure only, one frequency)."""
    n = tables.n
    fi, fg, fsv, fcv, om = tables.forcing
    if len(om) != 1:
        raise ValueError("one forcing frequency expected")
    fs, fc = np.zeros(n), np.zeros(n)
    np.add.at(fs, fi, fsv)
    np.add.at(fc, fi, fcv)
    nc = tables.cidx.shape[0]
    Gn, Gr = np.zeros((nc, n)), np.zeros((nc, n))
    for j in range(nc):
        for s in range(4):
            i = tables.cidx[j, s]
            if i >= 0:
                Gn[j, i] += tables.cgn[j, s]
                Gr[j, i] += tables.cgr[j, s]
    return ContactChain(1.0 / np.asarray(tables.invm, dtype=float), tables.stiffness_matrix(),
                        tables.damping_matrix(), fs, fc, float(om[0]), Gn, Gr,
                        np.asarray(tables.cgap, dtype=float).copy(), np.asarray(tables.ck, dtype=float).copy(),
                        np.broadcast_to(np.asarray(mu, dtype=float), (nc,)).copy())


@dataclass
class Assignment:
    """One stick/slip assignment tried by :meth:`CoulombReference.enumerate`."""

    modes: np.ndarray
    y: np.ndarray          # the state (projected if the assignment makes a contact newly stick)
    violation: float       # largest relative violation over the undetermined contacts (0 if none)
    N: np.ndarray
    f: np.ndarray
    arel: np.ndarray       # relative tangential accelerations
    stick_ok: bool = True  # every undetermined sticking contact has both stick guards >= 0


@dataclass
class ReferenceResult:
    sample_t: np.ndarray
    samples: np.ndarray
    final_state: np.ndarray
    final_modes: np.ndarray
    events: list = field(default_factory=list)   # (t, contact, from, to) per mode change
    n_problems: int = 0                             # friction problems solved
    max_cone_ratio: float = 0.0                     # largest |f| / mu N of a sticking contact at a sample or event


class CoulombReference:
    """Event-driven reference of a :class:`ContactChain` (see the module docstring).

    Parameters
    ----------
    chain : ContactChain
    rtol, atol : solve_ivp tolerances (``atol`` scalar or per state)
    max_step : largest step of ``solve_ivp`` (default ``T / 100``), so that a guard
        cannot cross zero twice unseen within one step
    v_tol : ``|v|`` at most this counts as zero (m/s)
    cone_tol, tie_tol : see the module docstring
    simultaneity_tol : at an event, a guard of the old modes that was on its starting side
        at the last step's start and is now within this fraction of the sum of its
        terms' magnitudes of zero fires too (a coincident root a rounding error short)
    """

    def __init__(self, chain: ContactChain, *, rtol: float = 1e-12, atol=1e-15, max_step: float | None = None,
                 v_tol: float = 1e-12, cone_tol: float = 1e-9, tie_tol: float = 1e-6,
                 simultaneity_tol: float = 1e-12):
        self.c = chain
        self.rtol, self.atol = rtol, atol
        self.max_step = chain.period / 100 if max_step is None else max_step
        self.v_tol, self.cone_tol, self.tie_tol = v_tol, cone_tol, tie_tol
        self.simultaneity_tol = simultaneity_tol
        self._W = chain.W
        self._cache: dict = {}

    # ---- forces and flow --------------------------------------------------------------
    def _linear(self, q, u, one, L, modes):
        """``N``, ``f``, ``acc`` for columns of ``q``, ``u``, ``L`` (``(n, p)``) and constants ``one`` (``(p,)``).

        Everything is linear in ``(q, u, 1, F)`` for fixed modes; called with the
        identity as columns it gives the affine maps of :meth:`_affine`.
        """
        c = self.c
        modes = np.asarray(modes)
        closed = (modes != OPEN).astype(float)[:, None]
        N = closed * c.k[:, None] * (c.Gn @ q - c.gap[:, None] * one[None, :])
        sgn = np.array([slip_sign(mj) if mj in (SLIP_P, SLIP_M) else 0.0 for mj in modes])
        f = (sgn * c.mu)[:, None] * N
        F = L - c.K @ q - c.C @ u - c.Gn.T @ N - c.Gr.T @ f
        S = np.flatnonzero(modes == STICK)
        if S.size:
            GS = c.Gr[S]
            fS = np.linalg.solve((GS / c.m) @ GS.T, GS @ (F / c.m[:, None]))
            f[S] = fS
            F = F - GS.T @ fS
        return N, f, F / c.m[:, None]

    def _affine(self, modes):
        """Per modes: matrices ``R_N, R_f, R_acc`` with ``N = R_N X`` etc., ``X = (q, u, 1, F(t))``."""
        key = tuple(int(x) for x in modes)
        out = self._cache.get(key)
        if out is None:
            n = self.c.n
            E = np.eye(3 * n + 1)
            N, f, acc = self._linear(E[:n], E[n:2 * n], E[2 * n], E[2 * n + 1:], key)
            out = self._cache[key] = (N, f, acc, self.c.Gr @ acc)
        return out

    def _X(self, t, y):
        n = self.c.n
        return np.concatenate([y[:2 * n], (1.0,), self.c.load(t)])

    def forces(self, t: float, y: np.ndarray, modes) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(N, f, acc, arel)``: normal and friction forces, accelerations, relative tangential ones."""
        X = self._X(t, y)
        return tuple(R @ X for R in self._affine(modes))

    def rhs(self, t, y, modes):
        n = self.c.n
        return np.concatenate([y[n:2 * n], self._affine(modes)[2] @ self._X(t, y)])

    def _flow(self, modes):
        """``rhs`` as a fast closure: ``y' = A y + b0 + bs sin(w t) + bc cos(w t)`` (same matrices)."""
        c = self.c
        n = c.n
        R = self._affine(modes)[2]
        A = np.zeros((2 * n, 2 * n))
        A[:n, n:] = np.eye(n)
        A[n:] = R[:, :2 * n]
        b0 = np.concatenate([np.zeros(n), R[:, 2 * n]])
        bs = np.concatenate([np.zeros(n), R[:, 2 * n + 1:] @ c.fs])
        bc = np.concatenate([np.zeros(n), R[:, 2 * n + 1:] @ c.fc])
        w = c.omega
        sin, cos = math.sin, math.cos

        def f(t, y):
            return A @ y + b0 + bs * sin(w * t) + bc * cos(w * t)
        return f

    def _event_rows(self, modes):
        """Guard ``i`` as ``g_y[i] . y + g0[i] + gs[i] sin(w t) + gc[i] cos(w t)``."""
        c = self.c
        n = c.n
        Rg = self._guard_matrix(modes)
        return Rg[:, :2 * n], Rg[:, 2 * n], Rg[:, 2 * n + 1:] @ c.fs, Rg[:, 2 * n + 1:] @ c.fc

    def project(self, y: np.ndarray, stick: np.ndarray) -> np.ndarray:
        """Velocities projected onto ``v_j = 0`` for the contacts ``stick`` (boolean mask)."""
        S = np.flatnonzero(stick)
        if not S.size:
            return y
        c = self.c
        n = c.n
        GS = c.Gr[S]
        u = y[n:2 * n]
        lam = np.linalg.solve((GS / c.m) @ GS.T, GS @ u)
        out = y.copy()
        out[n:2 * n] = u - (GS.T @ lam) / c.m
        return out

    # ---- guards -----------------------------------------------------------------------
    @staticmethod
    def guard_list(modes) -> list[tuple[int, str, int]]:
        """``(contact, kind, direction)`` of every guard of ``modes``."""
        out = []
        for j, mj in enumerate(modes):
            if mj == OPEN:
                out.append((j, "close", +1))
                continue
            out.append((j, "open", -1))
            if mj == STICK:
                out.append((j, "stick->slip+", -1))
                out.append((j, "stick->slip-", -1))
            else:
                out.append((j, "v=0", -1))
        return out

    def _guard_matrix(self, modes) -> np.ndarray:
        """Rows ``R_g`` with guard values ``R_g X`` (``X`` of :meth:`_affine`), in :meth:`guard_list` order."""
        key = ("g",) + tuple(int(x) for x in modes)
        out = self._cache.get(key)
        if out is None:
            c = self.c
            n = c.n
            R_N, R_f, _, _ = self._affine(modes)
            delta = np.concatenate([c.Gn, np.zeros((c.nc, n)), -c.gap[:, None], np.zeros((c.nc, n))], axis=1)
            vel = np.concatenate([np.zeros((c.nc, n)), c.Gr, np.zeros((c.nc, 1 + n))], axis=1)
            rows = []
            for j, kind, _ in self.guard_list(modes):
                if kind in ("close", "open"):
                    rows.append(delta[j])
                elif kind == "stick->slip+":
                    rows.append(c.mu[j] * R_N[j] - R_f[j])
                elif kind == "stick->slip-":
                    rows.append(c.mu[j] * R_N[j] + R_f[j])
                else:
                    rows.append(slip_sign(modes[j]) * vel[j])
            out = self._cache[key] = np.array(rows)
        return out

    def guard_values(self, t, y, modes) -> np.ndarray:
        return self._guard_matrix(modes) @ self._X(t, y)

    @staticmethod
    def _crossed(g0, g1, direction) -> bool:
        if direction < 0:
            return g0 >= 0.0 and g1 < 0.0
        return g0 <= 0.0 and g1 > 0.0

    # ---- the friction problem, by enumeration -------------------------------------------
    def enumerate(self, t: float, y: np.ndarray, modes, undetermined, was_stick=None) -> list[Assignment]:
        """Every assignment of ``{stick, slip+, slip-}`` to the contacts ``undetermined``.

        ``was_stick`` (mask, default none): contacts sticking before the event; an
        assignment that makes any other contact stick projects the velocities.
        """
        c = self.c
        U = list(undetermined)
        base = np.array(modes, dtype=np.int64)
        was_stick = np.zeros(c.nc, bool) if was_stick is None else np.asarray(was_stick, bool)
        out = []
        for combo in itertools.product(CLOSED_MODES, repeat=len(U)):
            cm = base.copy()
            cm[U] = combo
            stick = cm == STICK
            ya = self.project(y, stick) if np.any(stick & ~was_stick) else y.copy()
            N, f, _, arel = self.forces(t, ya, cm)
            g = self.guard_values(t, ya, cm)
            stick_ok = all(g[i] >= 0.0 for i, (j, kind, _) in enumerate(self.guard_list(cm))
                           if kind.startswith("stick") and j in U)
            viol = 0.0
            for j in U:
                bound = c.mu[j] * N[j]
                if cm[j] == STICK:
                    v = (abs(f[j]) - bound) / max(bound, 1e-300)
                else:
                    v = -slip_sign(cm[j]) * arel[j] / max(self._W[j, j] * bound, 1e-300)
                viol = max(viol, v)
            out.append(Assignment(cm, ya, viol, N, f, arel, stick_ok))
        return out

    def consistent(self, assignments: list[Assignment], undetermined, proposed=None) -> Assignment:
        """The consistent assignment (unique up to round-off ties), or :class:`FrictionProblemError`.

        Consistent: every sticking contact inside its cone, evaluated exactly as
        the stick guards are (no tolerance, so a stick guard never starts below
        zero, where ``solve_ivp`` could not see it fall), and every slipping
        contact's acceleration along its slip within ``cone_tol``. Among tied
        assignments (the same forces to ``tie_tol``), the ``proposed`` modes (what
        the fired guard asks for: slip after a stick guard, stick after ``v = 0``)
        are preferred, then the least violation.
        """
        ok = [a for a in assignments if a.stick_ok and a.violation <= self.cone_tol]
        if not ok:
            raise FrictionProblemError("no consistent stick/slip assignment: "
                                       + "; ".join(f"{a.modes.tolist()}: {a.violation:.3g}" for a in assignments))
        U = list(undetermined)
        prop = None if proposed is None else np.asarray(proposed)[U]
        best = min(ok, key=lambda a: (prop is None or not np.array_equal(a.modes[U], prop), a.violation))
        scale = max(float(np.max(self.c.mu[U] * best.N[U])), 1e-300)
        for a in ok:
            if np.max(np.abs(a.f[U] - best.f[U])) > self.tie_tol * scale:
                raise FrictionProblemError(f"two consistent assignments with different forces: {best.modes.tolist()} "
                                           f"f={best.f.tolist()} and {a.modes.tolist()} f={a.f.tolist()}")
        return best

    def settle(self, t, y, modes, undetermined, was_stick) -> tuple[np.ndarray, np.ndarray]:
        """Modes and (projected) state after the friction problem of ``undetermined`` (``modes``: proposed)."""
        if not len(undetermined):
            return np.array(modes, dtype=np.int64), y
        best = self.consistent(self.enumerate(t, y, modes, undetermined, was_stick), undetermined, modes)
        return best.modes, best.y

    def undetermined(self, y, modes, extra=()) -> list[int]:
        """Closed contacts that stick, that are listed in ``extra``, or whose ``|v| <= v_tol``."""
        c = self.c
        v = c.Gr @ y[c.n:2 * c.n]
        return [j for j in range(c.nc) if modes[j] != OPEN
                and (modes[j] == STICK or j in extra or abs(v[j]) <= self.v_tol)]

    def initial_modes(self, t: float, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Close every contact with ``delta >= 0`` (slip along ``v``; friction problem at ``v = 0``)."""
        c = self.c
        n = c.n
        delta = c.Gn @ y[:n] - c.gap
        v = c.Gr @ y[n:2 * n]
        modes = np.zeros(c.nc, dtype=np.int64)
        for j in range(c.nc):
            if delta[j] >= 0.0:
                modes[j] = SLIP_P if v[j] > 0 else SLIP_M if v[j] < 0 else STICK
        return self.settle(t, y, modes, self.undetermined(y, modes), np.zeros(c.nc, bool))

    def cone_ratio(self, t, y, modes) -> float:
        N, f, _, _ = self.forces(t, y, modes)
        r = 0.0
        for j in range(self.c.nc):
            if modes[j] == STICK:
                r = max(r, abs(f[j]) / (self.c.mu[j] * N[j]))
        return r

    # ---- the run ------------------------------------------------------------------------
    def run(self, y0, t_end: float, sample_times=(), t0: float = 0.0, max_events: int = 100_000) -> ReferenceResult:
        """Integrate from ``(t0, y0)`` to ``t_end``; states at ``sample_times`` (exact stops)."""
        c = self.c
        y = np.array(y0, dtype=float)
        t = float(t0)
        modes, y = self.initial_modes(t, y)
        res = ReferenceResult(np.array(sorted(sample_times), dtype=float), np.zeros((len(sample_times), 2 * c.n)),
                              y, modes)
        res.n_problems = 1
        stops = [s for s in res.sample_t if t0 < s <= t_end] + [t_end]
        k_sample = 0
        while k_sample < len(res.sample_t) and res.sample_t[k_sample] <= t0:
            res.samples[k_sample] = y
            k_sample += 1
        stop_i = 0
        n_ev = 0
        while t < t_end:
            while stops[stop_i] <= t:
                stop_i += 1
            t_stop = stops[stop_i]
            glist = self.guard_list(modes)
            cm = modes.copy()

            gy, g0, gs, gc = self._event_rows(cm)
            w = c.omega

            def make(i, d):
                gyi, g0i, gsi, gci = gy[i], float(g0[i]), float(gs[i]), float(gc[i])

                def ev(tt, yy):
                    return float(gyi @ yy) + g0i + gsi * math.sin(w * tt) + gci * math.cos(w * tt)
                ev.terminal = True
                ev.direction = d
                return ev
            events = [make(i, d) for i, (_, _, d) in enumerate(glist)]
            sol = solve_ivp(self._flow(cm), (t, t_stop), y, method="DOP853", rtol=self.rtol,
                            atol=self.atol, events=events, dense_output=True, max_step=self.max_step)
            if sol.status < 0:
                raise RuntimeError(f"solve_ivp failed at t = {t}: {sol.message}")
            if sol.status == 0:
                t, y = t_stop, sol.y[:, -1].copy()
                res.max_cone_ratio = max(res.max_cone_ratio, self.cone_ratio(t, y, modes))
                while k_sample < len(res.sample_t) and res.sample_t[k_sample] <= t:
                    res.samples[k_sample] = y
                    k_sample += 1
                continue
            # an event: the reported guard, taken strictly past its root
            te = sol.t[-1]
            i_rep = min((i for i in range(len(glist)) if sol.t_events[i].size),
                        key=lambda i: abs(sol.t_events[i][-1] - te))
            d = 0.0
            ye = sol.y_events[i_rep][-1].copy()
            for _ in range(200):
                g = self.guard_values(te + d, ye, cm)[i_rep]
                if (g < 0.0) if glist[i_rep][2] < 0 else (g > 0.0):
                    break
                d = max(2.0 * d, math.ulp(te))
                ye = sol.sol(te + d)
            else:
                raise RuntimeError(f"could not step past the root of {glist[i_rep]} at t = {te}")
            te = te + d
            # samples at or before the event (from the dense output of the old modes)
            while k_sample < len(res.sample_t) and res.sample_t[k_sample] <= te:
                res.samples[k_sample] = sol.sol(res.sample_t[k_sample])
                k_sample += 1
            # every guard of the old modes that is past zero, or at zero to round-off, fires (simultaneous
            # events: a guard whose root coincides with the reported one may lie a rounding error short)
            t_prev, y_prev = (sol.t[-2], sol.y[:, -2]) if sol.t.size >= 2 else (t, y)
            g0 = self.guard_values(t_prev, y_prev, cm)
            g1 = self.guard_values(te, ye, cm)
            eps = self.simultaneity_tol * (np.abs(self._guard_matrix(cm)) @ np.abs(self._X(te, ye)))
            fired = [i for i in range(len(glist))
                     if self._crossed(g0[i], g1[i], glist[i][2])
                     or (glist[i][2] * g0[i] < 0.0 and abs(g1[i]) <= eps[i])]
            if i_rep not in fired:
                fired.append(i_rep)
            new = modes.copy()
            extra = set()
            v = c.Gr @ ye[c.n:2 * c.n]
            for i in fired:
                j, kind, _ = glist[i]
                if kind == "open":
                    new[j] = OPEN
                elif kind == "close":
                    if abs(v[j]) > self.v_tol:
                        new[j] = SLIP_P if v[j] > 0 else SLIP_M
                    else:
                        new[j] = STICK
                        extra.add(j)
                elif kind == "v=0":   # proposed: stick; the friction problem decides
                    new[j] = STICK
                    extra.add(j)
                else:                 # a stick guard; proposed: that slip
                    new[j] = SLIP_P if kind == "stick->slip+" else SLIP_M
                    extra.add(j)
            for j in list(extra):
                if new[j] == OPEN:
                    extra.discard(j)
            U = self.undetermined(ye, new, extra)
            was_stick = modes == STICK
            new, ye = self.settle(te, ye, new, U, was_stick)
            if U:
                res.n_problems += 1
            for j in range(c.nc):
                if new[j] != modes[j]:
                    res.events.append((te, j, int(modes[j]), int(new[j])))
            n_ev += 1
            if n_ev > max_events:
                raise RuntimeError("too many events")
            t, y, modes = te, ye, new
            res.max_cone_ratio = max(res.max_cone_ratio, self.cone_ratio(t, y, modes))
        res.final_state, res.final_modes = y, modes
        return res
