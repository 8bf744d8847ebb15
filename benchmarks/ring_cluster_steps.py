"""Rings' replayed tangent with each cluster's step through its events compiled, against the Python one.

    python benchmarks/ring_cluster_steps.py [--repeats 2]

The replay (:mod:`blademodel.numeric.contact_tangent`) takes every step with events
through its clusters' sub-steps: the sub-step to each event and its derivatives, the
event time's derivative from the fired guard's gradient, the stick projection, the
sub-step on. *Before*: that sequence in Python around the compiled sub-steps and guard
differences (``ContactTangent._cluster_step``), about 100 µs a cluster step on a
mistuned 24-blade ring, half of a replay. *Now*: one compiled call a cluster step
(``cluster_step`` of :mod:`blademodel.numeric.contact_replay`), from a plan kept by the
cluster's rows, modes and transitions (``A``'s blocks, the guards' kept gradients, the
projections), its sub-steps evaluating the kernel's own cluster of the events (its active
set), giving the step's matrix on the cluster's rows, then one product with the block.
Laws with labels (Iwan): the plan is recorded from the Python step run once on no columns
(its blocks of ``A``, the labels each transition set, the resets' Jacobians for them).

Measured side by side, repeats interleaved, minimum CPU time of the process:

* one replay of a mistuned ring's period (its orbit at 1350 rad/s; 24, 48 and 96 blades), the step's matrices
  built afresh as a continuation's next point needs them (caches of ``R(hA)`` and its
  powers emptied; the modes' ``A`` and the plans kept, as from point to point), and of the
  README's preloaded 24-blade Iwan ring (``gap = -1e-5``) at 290 rad/s (the plans recorded
  by the first replay, as at a continuation's earlier points);
* continuations in ``omega`` of ``models/bladed_disk_24.yaml``: mistuned rings of 24 and
  48 blades (``mistuning_std = 0.02``, seed 1, whole map), the tuned bilinear ring
  (its openings and closings reset the law's state: in Python a call of the transition for
  each column of their differences) and the preloaded Iwan ring on its map reduced by the
  symmetry (``--cyclic``).

Checked: both ways give the same monodromy to rounding, and the same branches (field
values and leading multipliers' moduli) to ``1e-7``.
"""

from __future__ import annotations

import sys

import numpy as np

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parent))
import _common as C  # noqa: E402

from blademodel.config import apply_overrides, load_config  # noqa: E402
from blademodel.numeric import contact_tangent  # noqa: E402
from blademodel.numeric.kernels import make_integrator  # noqa: E402
from blademodel.orbits import find_periodic_orbit  # noqa: E402
from blademodel.orbits.period_map import PeriodMap  # noqa: E402

MISTUNED = {"mistuning_std": "0.02", "mistuning_seed": "1"}
IWAN = {"friction": "iwan", "gap": "-1e-5"}
CASES = {
    "24 blades, mistuned": (MISTUNED, dict(start=1300.0, stop=1340.0, grazing_tol=np.inf)),
    "48 blades, mistuned": ({"blades": "48", **MISTUNED},
                            dict(start=1300.0, stop=1320.0, grazing_tol=np.inf, max_points=16)),
    "24 blades, bilinear, tuned": ({"friction": "bilinear"}, dict(start=285.0, stop=290.0, max_points=40)),
    "24 blades, Iwan, preloaded, reduced map": (IWAN, dict(start=286.0, stop=288.0, cyclic=True)),
}
REPLAYS = {"24 blades, mistuned": {**MISTUNED, "omega": "1350"},
           "48 blades, mistuned": {"blades": "48", **MISTUNED, "omega": "1350"},
           "96 blades, mistuned": {"blades": "96", **MISTUNED, "omega": "1350"},
           "24 blades, Iwan, preloaded": {**IWAN, "omega": "290"}}


def compiled(on: bool, clear: bool = False) -> None:
    """Cluster steps compiled (``on``, the default) or in Python; with ``clear`` the kept matrices emptied."""
    contact_tangent.COMPILED_CLUSTER_STEPS = on
    if clear:
        contact_tangent._CACHES.clear()


def replay_rows(repeats: int) -> list:
    rows = []
    for name, overrides in REPLAYS.items():
        model = apply_overrides(load_config(C.ROOT / "models" / "bladed_disk_24.yaml"), overrides).build()
        orbit = find_periodic_orbit(model, transient=100)
        P = PeriodMap(make_integrator(model), 1, jacobian="tangent", workers=1)
        r = P.run(orbit.state, orbit.mode)
        tangent = contact_tangent.ContactTangent(P._ig)

        def replays(count=10):   # as a continuation's next point needs them: R(hA) and its powers afresh
            for _ in range(count):
                tangent._R = contact_tangent._Kept(contact_tangent.KEEP_BYTES // 8)
                tangent._powers = contact_tangent._Kept(contact_tangent.KEEP_BYTES // 8)
                M = tangent.monodromy(r.t, r.states, r.modes, r.log, r.n_log)
            return M

        ways = {"python": lambda: compiled(False), "compiled": lambda: compiled(True)}
        for way in ways.values():   # the plans and the modes' matrices kept, as from point to point
            way()
            replays(1)
        t, out = C.compare_ways(ways, replays, repeats)
        compiled(True)
        M, ref = out["compiled"], out["python"]
        rows.append({"case": f"one replay, {name}", "states": int(P.n), "events": int(r.events),
                     "before_s": t["python"] / 10, "now_s": t["compiled"] / 10, "gain": t["python"] / t["compiled"],
                     "difference": float(np.max(np.abs(M - ref)) / np.max(np.abs(ref)))})
        print(f"  {rows[-1]['case']}: {rows[-1]['gain']:.2f} x", flush=True)
    return rows


def main() -> int:
    args, t0 = C.start(__doc__)
    rows = replay_rows(args.repeats)
    for name, (overrides, opts) in CASES.items():
        C.ring_continuation(overrides, {**opts, "max_points": 2})   # compile (or load) the kernel before timing
        t, branches = C.compare_ways({"python": lambda: compiled(False, clear=True),
                                      "compiled": lambda: compiled(True, clear=True)},
                                     lambda: C.ring_continuation(overrides, opts), args.repeats)
        compiled(True)
        b = branches["compiled"]
        rows.append({"case": name, "states": int(b.states.shape[1]), "points": int(b.params.size),
                     "replays": int(b.replays), "before_s": t["python"], "now_s": t["compiled"],
                     "gain": t["python"] / t["compiled"], "difference": C.same(b, branches["python"])})
        print(f"  {name}: {rows[-1]['gain']:.2f} x", flush=True)
    print(C.table(rows, [("case", "case", "s"), ("states", "states", "d"), ("points", "points", "d"),
                         ("replays", "replays", "d"), ("before_s", "Python s", ".3f"),
                         ("now_s", "compiled s", ".3f"), ("gain", "gain", ".2f"),
                         ("difference", "differ by", ".1e")]))
    print(f"(CPU time of the process, min of {args.repeats} interleaved repeats; a replay: the mean of 10; a "
          "continuation: the first orbit included; the difference: of the monodromies, or of the branches' field "
          "values and leading multipliers' moduli, relative to the largest)")
    return C.finish("ring_cluster_steps", rows, args.repeats, t0)


if __name__ == "__main__":
    sys.exit(main())
