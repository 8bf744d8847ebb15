"""A bladed disk's period-map Jacobian: by its tangent, and by differences in threads against one thread.

    python benchmarks/ring_jacobian.py [--blades 8 24 48] [--repeats 3] [--points 6]

A ring's Jacobian by differences is ``2 n`` integrations of a period
(:meth:`blademodel.orbits.PeriodMap.differences`), shared among ``workers`` threads,
each with its own copy of the integrator's work arrays (the kernel releases the GIL
while it integrates); by the tangent (:mod:`blademodel.numeric.contact_tangent`) it is
one recorded integration and its replay, in one thread. For tuned Coulomb rings of ``models/bladed_disk_24.yaml``
(engine order 3, ``S = 600`` as on the docs' FRF, a state after 50 periods), the
Jacobian with one thread and with every CPU, repeats interleaved, minimum taken:

* *speed-up*: wall time with one thread / with every CPU (the time a user waits);
* *CPU overhead*: the process's CPU time (every thread) with every CPU / with one thread
  (what the threads cost on top, in contention and in copying work arrays).

And with forward differences (``jacobian="forward"``, ``n + 1`` integrations), every CPU:
its wall time against the central one's with every CPU, and how far its multipliers'
moduli are from the central ones'. And by the tangent: *cold* (the modes' matrices
derived first, as at a continuation's first point) and *warm* (kept, as at the later
points of a continuation in the frequency), its wall time against central differences
with every CPU, its CPU time against theirs, and its multipliers against the central
ones'.

Then a short continuation of the 24-blade ring in omega (``--points`` points from 280
rad/s) by central differences, one thread against every CPU, and by the tangent,
interleaved: the wall time per point. Every threaded Jacobian and branch is checked to
equal the one-thread one to the bit.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parent))
import _common as C  # noqa: E402

from blademodel.config import apply_overrides, load_config  # noqa: E402
from blademodel.numeric import contact_tangent  # noqa: E402
from blademodel.numeric.kernels import make_integrator  # noqa: E402
from blademodel.orbits import PeriodMap, continuation  # noqa: E402
from blademodel.orbits.period_map import worker_count  # noqa: E402

STEPS = 600


def ring(blades: int):
    return apply_overrides(load_config(C.ROOT / "models" / "bladed_disk_24.yaml"), {"blades": str(blades)})


def jacobian_rows(blades_list, repeats, workers):
    rows = []
    for blades in blades_list:
        ig, y, mode, scale = C.ring_state(ring(blades), STEPS)
        runs = {1: [], workers: [], "forward": [], "cold": [], "warm": []}
        ref = fwd = tan = None
        for _ in range(repeats):
            for w in runs:
                if w in ("cold", "warm"):
                    if w == "cold":
                        contact_tangent._CACHES.clear()
                    pm = PeriodMap(ig, jacobian="tangent")
                    tan, wall, cpu = C.clocks(lambda: pm.jacobian(y, mode, scale))
                    runs[w].append((wall, cpu))
                    continue
                pm = PeriodMap(ig, jacobian="forward", workers=workers) if w == "forward" else \
                    PeriodMap(ig, jacobian="differences", workers=w)
                J, wall, cpu = C.clocks(lambda: pm.differences(y, mode, scale))
                if w == "forward":
                    fwd = J
                else:
                    ref = J if ref is None else ref
                    if not np.array_equal(J, ref):
                        raise AssertionError(f"{blades} blades: the Jacobian with {w} threads differs from one thread's")
                runs[w].append((wall, cpu))
        one, many, forward, cold, warm = (min(runs[w]) for w in (1, workers, "forward", "cold", "warm"))
        cpu1, cpuw = min(c for _, c in runs[1]), min(c for _, c in runs[workers])
        mu_c, mu_f, mu_t = (np.sort(np.abs(np.linalg.eigvals(J)))[::-1] for J in (ref, fwd, tan))
        rows.append({"blades": blades, "states": y.size, "integrations": 2 * y.size, "wall_1": one[0],
                     "wall_w": many[0], "speedup": one[0] / many[0], "cpu_1": cpu1, "cpu_w": cpuw,
                     "cpu_overhead": cpuw / cpu1, "wall_forward": forward[0], "forward_gain": many[0] / forward[0],
                     "forward_mu1_error": abs(mu_f[0] - mu_c[0]), "forward_mu_error": float(np.max(np.abs(mu_f - mu_c))),
                     "wall_cold": cold[0], "wall_warm": warm[0], "cold_gain": many[0] / cold[0],
                     "warm_gain": many[0] / warm[0], "warm_cpu_gain": cpuw / warm[1],
                     "tangent_mu1_error": abs(mu_t[0] - mu_c[0]), "tangent_mu_error": float(np.max(np.abs(mu_t - mu_c)))})
        r = rows[-1]
        print(f"  {blades} blades: {r['speedup']:.2f} x faster, CPU x {r['cpu_overhead']:.2f}; forward "
              f"{r['forward_gain']:.2f} x faster again, |mu1| off by {r['forward_mu1_error']:.1e}; tangent "
              f"{r['cold_gain']:.2f} (cold) and {r['warm_gain']:.2f} (warm) x faster than central differences "
              f"in {workers} threads, |mu1| off by {r['tangent_mu1_error']:.1e}", flush=True)
    return rows


def branch_row(points, repeats, workers):
    cfg = ring(24)
    times = {1: [], workers: [], "tangent": []}
    ref = None
    for _ in range(repeats):
        for w in times:
            contact_tangent._CACHES.clear()
            jac, threads = ("tangent", 1) if w == "tangent" else ("differences", w)
            b, wall, cpu = C.clocks(lambda: continuation(cfg, "omega", 280.0, 292.0, max_points=points,
                                                       steps_per_period=STEPS, transient=50, workers=threads,
                                                       jacobian=jac))
            if w == "tangent":
                times[w].append((wall / len(b.params), cpu / len(b.params)))
                continue
            ref = b if ref is None else ref
            if not (np.array_equal(b.states, ref.states) and np.array_equal(b.multipliers, ref.multipliers)):
                raise AssertionError(f"the branch with {w} threads differs from one thread's")
            times[w].append((wall / len(b.params), cpu / len(b.params)))
    one, many, tan = min(times[1]), min(times[workers]), min(times["tangent"])
    return {"blades": 24, "points": len(ref.params), "wall_point_1": one[0], "wall_point_w": many[0],
            "speedup": one[0] / many[0], "cpu_point_1": one[1], "cpu_point_w": many[1], "wall_point_tangent": tan[0],
            "tangent_gain": many[0] / tan[0], "cpu_point_tangent": tan[1]}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--blades", type=int, nargs="+", default=[8, 24, 48])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--points", type=int, default=6, help="points of the 24-blade branch (0: none)")
    args = ap.parse_args()
    workers = worker_count(None)
    if workers < 2:
        print("one CPU only: nothing to compare")
        return 1
    C.print_load("at start")
    t0 = time.time()
    make_integrator(ring(4).build(), steps_per_period=STEPS)   # compile (or load) the kernel before timing
    rows = jacobian_rows(args.blades, args.repeats, workers)
    print(C.table(rows, [("blades", "blades", "d"), ("states", "states", "d"), ("integrations", "integrations", "d"),
                         ("wall_1", "1 thread s", ".2f"), ("wall_w", f"{workers} threads s", ".2f"),
                         ("speedup", "speed-up", ".2f"), ("cpu_overhead", "CPU overhead", ".2f"),
                         ("wall_forward", "forward s", ".2f"), ("forward_gain", "central / forward", ".2f"),
                         ("forward_mu1_error", "forward |mu1| error", ".1e"),
                         ("forward_mu_error", "largest |mu| error", ".1e"),
                         ("wall_cold", "tangent cold s", ".2f"), ("wall_warm", "tangent warm s", ".2f"),
                         ("warm_gain", f"central ({workers} threads) / warm tangent", ".2f"),
                         ("warm_cpu_gain", "same, CPU", ".2f"), ("tangent_mu_error", "tangent largest |mu| error", ".1e")]))
    branch = None
    if args.points > 0:
        branch = branch_row(args.points, max(1, args.repeats - 1), workers)
        print(f"24-blade ring, continuation ({branch['points']} points): {branch['wall_point_1']:.2f} s a point "
              f"with one thread, {branch['wall_point_w']:.2f} s with {workers}: {branch['speedup']:.2f} x faster; "
              f"by the tangent {branch['wall_point_tangent']:.2f} s: {branch['tangent_gain']:.2f} x faster than "
              f"{workers} threads")
    C.print_load("at end")
    path = C.write_json("ring_jacobian", {"benchmark": "ring_jacobian", "workers": workers, "steps_per_period": STEPS,
                                          "repeats": args.repeats, "jacobian": rows, "branch": branch,
                                          "machine": C.machine(), "elapsed_s": time.time() - t0})
    _plot(rows, branch, workers)
    print(f"wrote {path} and ring_jacobian.png")
    return 0


def _plot(rows, branch, workers):
    """Speed-ups against one thread's central differences, by ring size."""
    from matplotlib.figure import Figure
    fig = Figure(figsize=(6, 3.4))
    ax = fig.add_subplot(1, 1, 1)
    blades = np.array([r["blades"] for r in rows])
    x = np.arange(blades.size)
    threads = np.array([r["speedup"] for r in rows])
    forward = np.array([r["speedup"] * r["forward_gain"] for r in rows])
    tangent = np.array([r["speedup"] * r["warm_gain"] for r in rows])
    ax.bar(x - 0.27, threads, 0.27, label=f"central differences, {workers} threads")
    ax.bar(x, forward, 0.27, label=f"forward differences, {workers} threads")
    ax.bar(x + 0.27, tangent, 0.27, label="tangent (modes' matrices kept), 1 thread")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xticks(x, [f"{b} blades\n{r['states']} states" for b, r in zip(blades, rows)])
    ax.set_ylabel("wall-time speed-up of a Jacobian\nover central differences, 1 thread")
    title = "Period-map Jacobian of tuned Coulomb rings (S = 600)"
    if branch:
        title += (f"\n24-blade continuation, per point: {branch['speedup']:.2f} x faster with {workers} threads, "
                  f"{branch['speedup'] * branch['tangent_gain']:.2f} x by the tangent")
    ax.set_title(title, fontsize=8)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(C.OUT / "ring_jacobian.png", dpi=110)


if __name__ == "__main__":
    raise SystemExit(main())
