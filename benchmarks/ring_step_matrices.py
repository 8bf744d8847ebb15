"""A ring's continuation with each step matrix ``R(hA)`` from the mode's kept powers of ``A``, against Horner's rule.

    python benchmarks/ring_step_matrices.py [--repeats 2]

The replayed tangent of the per-contact kernel (:mod:`blademodel.numeric.contact_tangent`)
multiplies the monodromy by ``R(hA)`` of each step's mode, ``R`` the method's stability
polynomial (degree 4 for RK4). The step ``h = T / S`` moves with the excitation frequency
from point to point of a continuation in ``omega``, so ``R(hA)`` is computed afresh at every
replay for every mode it meets, while ``A`` is kept. *Before*: Horner's rule, ``d - 1``
products of the ring's size a mode (what sparse ``A``, from ``GROUPED_FROM`` states on, still
uses). *Now*: ``A, A^2, ..., A^d`` kept once a mode and combined at each step (one product
of the ``d`` scaled coefficients with them), for whole steps where ``A`` is dense and for
the clusters' sub-steps.

Two continuations of ``models/bladed_disk_24.yaml`` (96 states), before and now, repeats
interleaved, minimum CPU time of the process (BLAS threads included): a *mistuned* ring
(``mistuning_std = 0.02``, seed 1, whole map, ``omega`` 1420 to 1440 rad/s, many modes a
period: contacts switch at different instants), and the *tuned* ring on ``T / 8``
(``cyclic``, 280 to 290 rad/s). Checked: both ways give the same branch (its points, states
and multipliers to ``1e-7`` of the largest: the two sum the same polynomial in another order,
and the corrections, converged to a residual of ``1e-10``, take other paths from there).
"""

from __future__ import annotations

import sys

import numpy as np

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parent))
import _common as C  # noqa: E402

from blademodel.numeric import contact_tangent  # noqa: E402

_POWERS_BELOW = contact_tangent.POWERS_BELOW

CASES = {
    "mistuned (whole map)": ({"mistuning_std": "0.02", "mistuning_seed": "1"},
                             dict(start=1420.0, stop=1440.0, grazing_tol=np.inf)),
    "tuned (T / 8)": ({}, dict(start=280.0, stop=290.0, cyclic=True)),
}


def now(on: bool) -> None:
    """Step matrices from kept powers (``on``, the default) or by Horner's rule (before); caches emptied."""
    contact_tangent.POWERS_BELOW = _POWERS_BELOW if on else 0
    contact_tangent._CACHES.clear()


def run(overrides, opts):
    return C.ring_continuation(overrides, {"max_points": 400, "workers": 1, **opts})


def same(a, b) -> float:
    """The largest difference of two branches' states and multipliers, relative to their largest entries (inf where
    their points differ in number)."""
    if a.params.size != b.params.size:
        return np.inf
    return max(float(np.max(np.abs(a.params - b.params)) / np.max(np.abs(a.params))),
               float(np.max(np.abs(a.states - b.states)) / np.max(np.abs(a.states))),
               float(np.max(np.abs(a.multipliers - b.multipliers)) / np.max(np.abs(a.multipliers))))


def main() -> int:
    args, t0 = C.start(__doc__)
    rows = []
    for name, (overrides, opts) in CASES.items():
        run(overrides, {**opts, "stop": opts["start"] + 0.5})   # compile (or load) the kernels before timing
        t, branches = C.compare_ways({"before": lambda: now(False), "now": lambda: now(True)},
                                     lambda: run(overrides, opts), args.repeats)
        now(True)
        b = branches["now"]
        rows.append({"case": name, "points": int(b.params.size), "replays": int(b.replays),
                     "before_s": t["before"], "now_s": t["now"], "gain": t["before"] / t["now"],
                     "difference": same(b, branches["before"])})
        print(f"  {name}: {rows[-1]['gain']:.2f} x", flush=True)
    print(C.table(rows, [("case", "24-blade ring", "s"), ("points", "points", "d"), ("replays", "replays", "d"),
                         ("before_s", "Horner s", ".2f"), ("now_s", "kept powers s", ".2f"),
                         ("gain", "gain", ".2f"), ("difference", "branches differ by", ".1e")]))
    print(f"(continuation in omega, CPU time of the process, min of {args.repeats} interleaved repeats; the "
          "difference: states, multipliers and field values, relative to the largest)")
    return C.finish("ring_step_matrices", rows, args.repeats, t0)


if __name__ == "__main__":
    sys.exit(main())
