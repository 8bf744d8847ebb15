"""A forced-response curve by continuation against a brute-force sweep of the same points.

    python benchmarks/frf.py [--points 200] [--repeats 2]

The paper's pair (Coulomb and bilinear, base case) with the excitation frequency swept
from 250 to 350 rad/s (the paper's 290 inside). Continuation
(:func:`blademodel.orbits.continuation`, RK4, ``S = 1000``) gives each point's orbit to a
scaled residual of ``1e-10``, with its bifurcations located; its step is capped at
``1 / --points``. Two brute-force sweeps visit the *same* values:

* *fixed*: each value from rest, 200 periods discarded (``simulate``'s default), one
  recorded, as ``blademodel sweep`` runs a study;
* *from rest*: each value from rest, period by period until two successive Poincaré
  samples agree to ``1e-10`` of each state's scale (the continuation's accuracy), at most
  1000 periods a value (a point whose attractor is not period 1 never settles): brute
  force that stops as soon as it has the accuracy;
* *adaptive*: the same, each value from the previous value's last state (a warm start):
  the cheapest honest sweep.

The 200 periods of the fixed sweep do not reach the accuracy everywhere (slow settling
near a period doubling): a fixed sweep that does needs the transient of the slowest point
that settles from rest. It is not run; its cost is the measured fixed sweep's scaled by
the periods (the cost of a sweep is proportional to the periods it integrates).

Reported: the first-harmonic amplitudes of ``x1`` of each against the continuation's,
the periods integrated, and the CPU time (thread time, repeats interleaved, minimum),
also of the continuation with the period map differentiated by central differences
instead of its tangent. Every integrator after the first of a run is the first with its
parameters changed (``with_parameters``), in the sweeps as in the continuation.

Also measured (interleaved, at the branch's middle point): one recorded run of the period
map as the continuation's residuals make it and one replay of its tangent; from them the
ratio the continuation would have against the accuracy-matched fixed sweep if its time
were only the kernel's work (its integrations and replays, nothing around them), and if
every point took the least any can (two runs and a replay).

Goal (the issue "Periodic orbits"): continuation at least 20 x cheaper than a sweep of
the same resolution and accuracy.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parent))
import _common as C  # noqa: E402

from blademodel.config import apply_overrides  # noqa: E402
from blademodel.zheng2022 import BladePair
from blademodel.numeric.kernels import make_integrator  # noqa: E402
from blademodel.orbits import PeriodMap, continuation  # noqa: E402

START, STOP, TOL = 250.0, 350.0, 1e-10
MAX_PERIODS = 1000
GOAL = 20.0


def by_continuation(cfg, points, jacobian="auto"):
    # one thread: the clock is the thread's CPU time, and the sweeps run in one thread too
    return continuation(cfg, "omega", START, STOP, ds=0.5 / points, ds_max=1.0 / points, tol=TOL,
                        max_points=20 * points, jacobian=jacobian, workers=1)


class _Integrators:
    """The pair's integrator at any omega: built once, then its parameters changed (as continuation does)."""

    def __init__(self, cfg):
        self.cfg, self.first = cfg, None

    def at(self, w):
        model = apply_overrides(self.cfg, {"omega": float(w)}).build()
        if self.first is None:
            self.first = make_integrator(model)
            return self.first
        return self.first.with_parameters(model)


FIXED_TRANSIENT = 200


def kernel_costs(cfg, branch, calls: int = 300, repeats: int = 3) -> tuple:
    """Thread time of one recorded run of the period map (every step recorded and every event logged, as the
    continuation's residuals run it, with the map's own Python) and of one replay of its tangent, at the branch's
    middle point: ``(run, replay)`` in seconds, each the least over ``repeats`` interleaved means of ``calls``."""
    k = len(branch.params) // 2
    ig = _Integrators(cfg).at(float(branch.params[k]))
    P = PeriodMap(ig, 1)
    y, mode = branch.states[k].copy(), int(branch.modes[k][0])
    ys = (y, y * (1.0 + 1e-12))   # two starts, so that no run is the map's kept last run

    def runs():
        for i in range(calls):
            P.run(ys[i % 2], mode)

    def replays():
        P.run(y, mode)   # kept: each call below replays it
        for _ in range(calls):
            P.derivatives(y, mode)

    times = C.interleaved({"run": runs, "replay": replays}, repeats)
    return min(times["run"]) / calls, min(times["replay"]) / calls


def by_fixed_sweep(cfg, values, transient=FIXED_TRANSIENT):
    """Each value from rest, ``transient`` periods, then one period recorded: ``(harmonics, periods)``."""
    harmonics = []
    igs = _Integrators(cfg)
    for w in values:
        ig = igs.at(w)
        y = np.zeros(ig.n_state)
        mode = ig.mode_of(y)
        status, mode, _ = ig.advance(y, mode, 0, transient)
        harmonics.append(_harmonic(ig, y, mode))
    return np.array(harmonics), len(values) * (transient + 1)


def _harmonic(ig, y, mode):
    """First-harmonic amplitude of x1 over one period from ``(y, mode)``."""
    rec = ig.record_buffer(ig.steps_per_period + 1)
    ig.advance(y.copy(), mode, 0, 1, n_transient=0, record=rec)
    x = rec[1][:-1, 0]
    return abs(2 * np.fft.rfft(x)[1] / x.size)


def by_sweep(cfg, values, scale, warm=True):
    """Each value from the last one's state (``warm``) or from rest, until successive Poincaré samples agree to
    TOL of the scale: ``(harmonics, periods integrated at each value)``."""
    y, mode, periods, harmonics = None, None, [], []
    igs = _Integrators(cfg)
    for w in values:
        ig = igs.at(w)
        if y is None or not warm:
            y = np.zeros(ig.n_state)
            mode = ig.mode_of(y)
        prev = y[:scale.size].copy()
        periods.append(0)
        for k in range(MAX_PERIODS):   # a point that never settles (a period-2 attractor) stops here
            status, mode, _ = ig.advance(y, mode, 0, 1)
            periods[-1] += 1
            if status != 0:
                raise RuntimeError(f"integration failed at omega = {w}")
            if np.max(np.abs(y[:scale.size] - prev) / scale) <= TOL:
                break
            prev = y[:scale.size].copy()
        harmonics.append(_harmonic(ig, y, mode))
    return np.array(harmonics), np.array(periods)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--points", type=int, default=200)
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    C.print_load("at start")
    t_start = time.time()
    rows, results = [], {}
    for law in ("coulomb", "bilinear"):
        cfg = BladePair(friction=law)
        by_continuation(cfg, 5)        # compile (or load) the kernel before timing
        branch = by_continuation(cfg, args.points)
        values = branch.params[(branch.params >= START) & (branch.params <= STOP)]
        scale = np.max(np.abs(branch.states), axis=0)
        scale = np.maximum(scale, 1e-3 * scale.max())
        h_sweep, periods = by_sweep(cfg, values, scale)
        h_rest, rest_each = by_sweep(cfg, values, scale, warm=False)
        periods, periods_rest = int(periods.sum()), int(rest_each.sum())
        # the transient a fixed sweep needs for every point to reach the accuracy: the slowest from-rest
        # point that settles (points that never settle, on unstable period-1 orbits, left out)
        need = int(rest_each[rest_each < MAX_PERIODS].max())
        h_fixed, periods_fixed = by_fixed_sweep(cfg, values)
        i = branch.state_names.index("x1")
        inside = (branch.params >= START) & (branch.params <= STOP)
        h_cont = np.abs(branch.harmonics[:, i])[inside]
        stable = branch.stable[inside]
        agree = float(np.max(np.abs(h_sweep - h_cont)[stable] / h_cont[stable]))
        agree_median = float(np.median(np.abs(h_sweep - h_cont)[stable] / h_cont[stable]))
        agree_fixed = float(np.max(np.abs(h_fixed - h_cont)[stable] / h_cont[stable]))
        agree_rest = float(np.max(np.abs(h_rest - h_cont)[stable] / h_cont[stable]))
        times = C.interleaved({"continuation": lambda: by_continuation(cfg, args.points),
                               "differences": lambda: by_continuation(cfg, args.points, "differences"),
                               "sweep": lambda: by_sweep(cfg, values, scale),
                               "rest": lambda: by_sweep(cfg, values, scale, warm=False),
                               "fixed": lambda: by_fixed_sweep(cfg, values)}, args.repeats)
        t_c, t_s, t_f = min(times["continuation"]), min(times["sweep"]), min(times["fixed"])
        t_r = min(times["rest"])
        # that fixed sweep, costed from the measured one (its cost is proportional to the periods integrated)
        t_u = t_f * (need + 1) / (FIXED_TRANSIENT + 1)
        t_d = min(times["differences"])
        # the bounds the kernel's own work sets against the accuracy-matched fixed sweep: the branch's integrations
        # and replays at their measured cost, and the least any continuation point can take (two runs, the residual
        # at the prediction and one correction, and the replay for its multipliers)
        t_run, t_replay = kernel_costs(cfg, branch)
        t_kernel = branch.integrations * t_run + branch.replays * t_replay
        t_floor = len(branch.params) * (2 * t_run + t_replay)
        rows.append({"law": law, "points": len(values), "unstable": int(np.sum(~stable)),
                     "integrations": branch.integrations / len(branch.params),
                     "replays": branch.replays / len(branch.params),
                     "special": len(branch.special), "agree": agree, "agree_median": agree_median,
                     "agree_fixed": agree_fixed, "agree_rest": agree_rest, "t_differences": t_d,
                     "tangent_gain": t_d / t_c, "sweep_periods": periods, "rest_periods": periods_rest,
                     "fixed_periods": periods_fixed, "t_cont": t_c, "t_sweep": t_s, "t_rest": t_r,
                     "t_fixed": t_f, "ratio": t_s / t_c, "ratio_rest": t_r / t_c, "ratio_fixed": t_f / t_c,
                     "uniform_transient": need, "t_uniform": t_u, "ratio_uniform": t_u / t_c,
                     "t_run_us": 1e6 * t_run, "t_replay_us": 1e6 * t_replay, "t_kernel": t_kernel,
                     "kernel_share": t_kernel / t_c, "bound_kernel": t_u / t_kernel,
                     "bound_floor": t_u / t_floor})
        results[law] = {"omega": values, "harmonic_continuation": h_cont, "harmonic_sweep": h_sweep,
                        "harmonic_rest": h_rest, "harmonic_fixed": h_fixed, "stable": stable,
                        "special": [(p.kind, p.param) for p in branch.special]}
        print(f"  {law}: {len(values)} points, {len(branch.special)} special points; CPU sweep/continuation "
              f"{t_f / t_c:.2f} (fixed), {t_r / t_c:.2f} (from rest), {t_s / t_c:.2f} (adaptive)", flush=True)
    print(f"FRF of the pair, omega = {START:g} ... {STOP:g} rad/s, each point to {TOL:g} (CPU: min of "
          f"{args.repeats} interleaved repeats, thread time)")
    print(C.table(rows, [("law", "law", "s"), ("points", "points", "d"), ("unstable", "unstable", "d"),
                         ("special", "special points", "d"), ("integrations", "integrations a point", ".2f"),
                         ("replays", "replays a point", ".2f"), ("agree", "H1 adaptive vs cont.", ".1e"),
                         ("agree_median", "median", ".1e"),
                         ("agree_fixed", "H1 fixed vs cont.", ".1e"), ("agree_rest", "H1 from rest vs cont.", ".1e"),
                         ("sweep_periods", "adaptive periods", "d"), ("rest_periods", "from-rest periods", "d"),
                         ("fixed_periods", "fixed periods", "d"), ("t_cont", "continuation s", ".2f"),
                         ("t_sweep", "adaptive s", ".2f"), ("t_rest", "from rest s", ".2f"), ("t_fixed", "fixed s", ".2f"),
                         ("ratio_fixed", "fixed / cont.", ".2f"), ("uniform_transient", "transient for the accuracy", "d"),
                         ("ratio_uniform", "that fixed sweep / cont.", ".2f"), ("ratio_rest", "from rest / cont.", ".2f"),
                         ("ratio", "adaptive / cont.", ".2f"), ("tangent_gain", "differences / tangent", ".2f"),
                         ("t_run_us", "a recorded run us", ".0f"), ("t_replay_us", "a replay us", ".0f"),
                         ("kernel_share", "kernel work / cont.", ".2f"),
                         ("bound_kernel", "bound: kernel work alone", ".1f"),
                         ("bound_floor", "bound: 2 runs + 1 replay a point", ".1f")]))
    print("(H1 agreement over the stable points, largest and median; an unstable orbit is not what a sweep lands "
          "on. 'differences / tangent': the same continuation with the period map differentiated by central "
          "differences instead of its tangent)")
    print("(bounds: the accuracy-matched fixed sweep against the branch's integrations and replays at the "
          "measured cost of each and nothing else, and against two runs and a replay a point, the least a "
          "continuation point takes; 'kernel work / cont.': the share of the continuation's time they are)")
    print("('transient for the accuracy': the periods the slowest point that settles needs from rest; a fixed "
          "sweep with that transient is costed from the measured 200-period one, its cost being proportional to "
          "the periods)")
    for name, key in (("fixed-transient (200 periods)", "ratio_fixed"),
                      ("fixed-transient with the transient the accuracy needs", "ratio_uniform"),
                      ("from-rest adaptive", "ratio_rest"), ("adaptive warm-started", "ratio")):
        worst = min(r[key] for r in rows)
        print(f"Goal continuation >= {GOAL:g} x cheaper than the {name} sweep: "
              f"{'MET' if worst >= GOAL else 'MISSED'} (worst {worst:.2f} x)")
    C.print_load("at end")
    path = C.write_json("frf", {"benchmark": "frf", "rows": rows, "goal": GOAL, "machine": C.machine(),
                                "elapsed_s": time.time() - t_start,
                                "curves": {k: {kk: np.asarray(vv).tolist() for kk, vv in v.items()}
                                           for k, v in results.items()}})
    _plot(results, rows)
    print(f"wrote {path} and frf.png")
    return 0


def _plot(results, rows):
    from matplotlib.figure import Figure
    fig = Figure(figsize=(9, 3.6))
    for j, (law, r) in enumerate(results.items()):
        ax = fig.add_subplot(1, 2, j + 1)
        w, hc, hs, st = (np.asarray(r[k]) for k in ("omega", "harmonic_continuation", "harmonic_sweep", "stable"))
        ax.plot(w, hc * 1e6, "-", color="C0", lw=1.5, label="continuation")
        ax.plot(w, hs * 1e6, ".", color="C3", ms=3, label="adaptive sweep (same points)")
        if (~st).any():
            ax.plot(w[~st], hc[~st] * 1e6, "x", color="k", ms=4, label="unstable")
        row = next(x for x in rows if x["law"] == law)
        ax.set_title(f"{law}: CPU sweep / continuation = {row['ratio_fixed']:.1f} (fixed), "
                     f"{row['ratio_rest']:.1f} (from rest), {row['ratio']:.2f} (warm)", fontsize=8)
        ax.set_xlabel("ω (rad/s)")
        ax.set_ylabel("first harmonic of x1 (µm)")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(C.OUT / "frf.png", dpi=110)


if __name__ == "__main__":
    raise SystemExit(main())
