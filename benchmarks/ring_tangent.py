"""A bladed disk's replayed tangent: each mode's matrices by column groups and kept sparse, against column by column.

    python benchmarks/ring_tangent.py [--blades 24 48 96] [--repeats 2] [--points 8]

The replay (:mod:`blademodel.numeric.contact_tangent`) takes each contact mode's flow
matrix ``A = df/dy`` and each guard's gradient from differences of the compiled ``rhs``
and guards at the zero state. Column by column that is ``n + 1`` calls a mode; with the
model's pattern (:mod:`blademodel.numeric.contact_flow_pattern`) columns that share no
row go in one call, a guard's gradient takes only the columns it can depend on, and ``A``
is kept as a sparse matrix: from ``GROUPED_FROM`` states on. *Before*: column by column,
kept dense (the replay until this benchmark was written, and still below the threshold);
*now*: the defaults (so the rows below the threshold compare the same code, a check of the
noise).

For tuned Coulomb rings of ``models/bladed_disk_24.yaml`` (engine order ``N / 8``, ``S =
600``, a state after 50 periods), the Jacobian of the period map by the tangent, *cold*
(every mode's matrices computed, as at a continuation's first point) and *warm* (kept, as
at its later points), before and now, repeats interleaved, minimum taken; the two
monodromy matrices are checked to agree to rounding (``1e-12`` of the largest entry: a
sparse ``A`` sums the step matrices' products in another order). Then a short
continuation of the largest ring in ``omega`` both ways, wall time a point (the same
branch to ``1e-9``, the continuation's own tolerance being ``1e-10`` on a residual).
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

STEPS = 600
_GROUPED_FROM = contact_tangent.GROUPED_FROM


def ring(blades: int):
    return apply_overrides(load_config(C.ROOT / "models" / "bladed_disk_24.yaml"),
                           {"blades": str(blades), "engine_order": str(max(1, blades // 8))})


def now(on: bool) -> None:
    """The replay as it is (``on``), or as before: every column on its own, ``A`` kept dense (as below the
    threshold)."""
    contact_tangent.GROUPED_FROM = _GROUPED_FROM if on else 1 << 62
    contact_tangent._CACHES.clear()


def jacobian_rows(blades_list, repeats):
    rows = []
    for blades in blades_list:
        ig, y, mode, scale = C.ring_state(ring(blades), STEPS)
        t = {(g, k): [] for g in (True, False) for k in ("cold", "warm")}
        found, kept_bytes, modes = {}, {}, {}
        for _ in range(repeats):
            for g in (True, False):
                now(g)
                pm = PeriodMap(ig, jacobian="tangent", workers=1)
                J, wall, _ = C.clocks(lambda: pm.jacobian(y, mode, scale))
                t[g, "cold"].append(wall)
                J, wall, _ = C.clocks(lambda: pm.jacobian(y, mode, scale))
                t[g, "warm"].append(wall)
                found[g] = J
                kept = contact_tangent._caches(ig)["A"]
                modes[g], kept_bytes[g] = len(kept), kept.size
        if np.max(np.abs(found[True] - found[False])) > 1e-12 * np.max(np.abs(found[False])):
            raise AssertionError(f"{blades} blades: the monodromy now differs from the one before")
        n = ig.n_physical
        rows.append({"blades": blades, "states": n, "modes": modes[True], "modes_kept_before": modes[False],
                     "cold_before": min(t[False, "cold"]), "cold_now": min(t[True, "cold"]),
                     "cold_gain": min(t[False, "cold"]) / min(t[True, "cold"]),
                     "warm_before": min(t[False, "warm"]), "warm_now": min(t[True, "warm"]),
                     "warm_gain": min(t[False, "warm"]) / min(t[True, "warm"]),
                     "A_MB_now": kept_bytes[True] / 1e6, "A_MB_before": kept_bytes[False] / 1e6})
        print(f"  {blades} blades: cold {rows[-1]['cold_gain']:.2f} x, warm {rows[-1]['warm_gain']:.2f} x faster "
              f"now", flush=True)
    now(True)
    return rows


def branch_row(blades, points, repeats):
    cfg = ring(blades)
    runs = {True: [], False: []}
    ref = None
    for _ in range(repeats):
        for g in (True, False):
            now(g)
            b, wall, cpu = C.clocks(lambda: continuation(cfg, "omega", 280.0, 300.0, max_points=points,
                                                       steps_per_period=STEPS, transient=50, workers=1))
            if ref is None:
                ref = b
            elif b.params.size != ref.params.size or np.max(np.abs(b.states - ref.states)) > 1e-9 * np.max(
                    np.abs(ref.states)):
                raise AssertionError("the branch now differs from the one before")
            runs[g].append((wall / len(b.params), cpu / len(b.params)))
    now(True)
    one, many = min(runs[False]), min(runs[True])
    return {"blades": blades, "points": len(ref.params), "wall_point_before": one[0], "wall_point_now": many[0],
            "gain": one[0] / many[0], "cpu_point_before": one[1], "cpu_point_now": many[1]}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--blades", type=int, nargs="+", default=[24, 48, 96])
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--points", type=int, default=8, help="points of the largest ring's branch (0: none)")
    args = ap.parse_args()
    C.print_load("at start")
    t0 = time.time()
    make_integrator(ring(8).build(), steps_per_period=STEPS)   # compile (or load) the kernel before timing
    rows = jacobian_rows(args.blades, args.repeats)
    print(C.table(rows, [("blades", "blades", "d"), ("states", "states", "d"), ("modes", "modes met", "d"), ("modes_kept_before", "kept before", "d"),
                         ("cold_before", "cold, before s", ".2f"), ("cold_now", "cold, now s", ".2f"),
                         ("cold_gain", "cold gain", ".2f"), ("warm_before", "warm, before s", ".3f"),
                         ("warm_now", "warm, now s", ".3f"), ("warm_gain", "warm gain", ".2f"),
                         ("A_MB_before", "A kept before MB", ".1f"), ("A_MB_now", "A kept now MB", ".1f")]))
    print("(the Jacobian of the period map by the replayed tangent, wall time; before: column by column, A kept "
          "dense; now: grouped, kept sparse, from GROUPED_FROM states on; the monodromy the same to 1e-12)")
    result = {"benchmark": "ring_tangent", "steps_per_period": STEPS, "repeats": args.repeats, "jacobian": rows}
    if args.points:
        b = branch_row(max(args.blades), args.points, args.repeats)
        result["branch"] = b
        print(f"{b['blades']}-blade ring, continuation ({b['points']} points): {b['wall_point_before']:.2f} s a "
              f"point before, {b['wall_point_now']:.2f} s now: {b['gain']:.2f} x faster (the same branch)")
    _plot(rows, result.get("branch"))
    result["machine"], result["elapsed_s"] = C.machine(), time.time() - t0
    print(f"written {C.write_json('ring_tangent', result)}")
    return 0


def _plot(rows, branch):
    """Cold and warm gains by ring size, and the kept bytes of ``A`` before and now."""
    from matplotlib.figure import Figure
    fig = Figure(figsize=(7, 3.2))
    ax, bx = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    x = np.arange(len(rows))
    labels = [f"{r['blades']} blades\n{r['states']} states" for r in rows]
    ax.bar(x - 0.2, [r["cold_gain"] for r in rows], 0.4, label="cold (matrices computed)")
    ax.bar(x + 0.2, [r["warm_gain"] for r in rows], 0.4, label="warm (matrices kept)")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xticks(x, labels)
    ax.set_ylabel("replay, before / now (wall time)")
    title = "the tangent's replay, now against before"
    if branch:
        title += f"\n{branch['blades']}-blade continuation: {branch['gain']:.2f} x faster a point"
    ax.set_title(title, fontsize=8)
    ax.legend(fontsize=7)
    bx.bar(x - 0.2, [r["A_MB_before"] for r in rows], 0.4, label="before: dense, column by column")
    bx.bar(x + 0.2, [r["A_MB_now"] for r in rows], 0.4, label="now: sparse, grouped (from 128 states)")
    bx.set_xticks(x, labels)
    bx.set_ylabel("modes' A kept (MB; budget 512)")
    bx.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(C.OUT / "ring_tangent.png", dpi=110)


if __name__ == "__main__":
    sys.exit(main())
