"""Large rings' continuation with sparse whole-step matrices ``R(hA)``, against dense ones.

    python benchmarks/ring_sparse_steps.py [--repeats 2]

From ``GROUPED_FROM`` states on (32 blades) a mode's ``A`` is sparse, and the replayed tangent
(:mod:`blademodel.numeric.contact_tangent`) multiplies the monodromy by each step's
``R(hA)``. *Before*: ``R(hA)`` by Horner's rule, dense, so that every step with an event
cost a dense product of the ring's size, and every run of whole steps without events the
dense power of ``R`` by squaring and a dense product. *Now*, from ``SPARSE_STEPS_FROM``
states on: ``R(hA)`` sparse (its polynomial couples a blade to the four either side: 11 nonzeros a row at
48 and 96 blades), its product with the monodromy a fraction of the dense one's cost, and runs
up to ``SPARSE_RUN_MAX`` steps applied step by step; ``R(hA)`` assembled from the mode's kept
powers of ``A`` on their common pattern (one combination of their values), or (*sparse,
Horner*, measured beside it) by Horner's rule in sparse products at every replay, as the
step moves from point to point.

Three continuations of ``models/bladed_disk_24.yaml`` in ``omega``, before and now, repeats
interleaved, minimum CPU time of the process (BLAS threads included): mistuned rings
(``mistuning_std = 0.02``, seed 1, whole map: contacts switch at different instants, many
events a period) of 48 and 96 blades, and the README's tuned 96-blade ring at engine order
12 on ``T / 8`` through its period doubling. Checked: both ways give the same branch (its
field values and leading multipliers' moduli, to ``1e-7``: the two sum the same products in
another order, and the corrections, converged to ``1e-10``, take other paths from there).
"""

from __future__ import annotations

import sys

import numpy as np

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parent))
import _common as C  # noqa: E402

from blademodel.numeric import contact_tangent  # noqa: E402

_SPARSE_FROM = contact_tangent.SPARSE_STEPS_FROM

CASES = {
    "48 blades, mistuned": ({"blades": "48", "mistuning_std": "0.02", "mistuning_seed": "1"},
                            dict(start=1300.0, stop=1320.0, grazing_tol=np.inf, max_points=16)),
    "96 blades, mistuned": ({"blades": "96", "mistuning_std": "0.02", "mistuning_seed": "1"},
                            dict(start=1300.0, stop=1320.0, grazing_tol=np.inf, max_points=8)),
    "96 blades, tuned (T / 8)": ({"blades": "96", "engine_order": "12"},
                                 dict(start=272.2, stop=272.35, steps_per_period=600, cyclic=True)),
}


_KEPT_POWERS = contact_tangent.ContactTangent._whole_step_matrix


def _horner(self, h, cm, y):
    return contact_tangent.sparse_stability_matrix(h * self.flow_matrix(cm, y), self._poly)


def now(way: str) -> None:
    """Step matrices ``"dense"`` (before), ``"horner"`` (sparse, by Horner's rule) or ``"powers"`` (sparse, from
    kept powers: the default); caches emptied."""
    contact_tangent.SPARSE_STEPS_FROM = 10 ** 9 if way == "dense" else _SPARSE_FROM
    contact_tangent.ContactTangent._whole_step_matrix = _horner if way == "horner" else _KEPT_POWERS
    contact_tangent._CACHES.clear()


def main() -> int:
    args, t0 = C.start(__doc__)
    rows = []
    for name, (overrides, opts) in CASES.items():
        C.ring_continuation(overrides, {**opts, "max_points": 2})   # compile (or load) the kernel before timing
        t, branches = C.compare_ways({w: (lambda w=w: now(w)) for w in ("dense", "horner", "powers")},
                                     lambda: C.ring_continuation(overrides, opts), args.repeats)
        now("powers")
        b = branches["powers"]
        rows.append({"case": name, "states": int(b.states.shape[1]), "points": int(b.params.size),
                     "replays": int(b.replays), "before_s": t["dense"], "horner_s": t["horner"], "now_s": t["powers"],
                     "gain_horner": t["dense"] / t["horner"], "gain": t["dense"] / t["powers"],
                     "difference": max(C.same(b, branches["dense"]), C.same(b, branches["horner"]))})
        print(f"  {name}: {rows[-1]['gain']:.2f} x", flush=True)
    print(C.table(rows, [("case", "ring", "s"), ("states", "states", "d"), ("points", "points", "d"),
                         ("replays", "replays", "d"), ("before_s", "dense s", ".1f"),
                         ("horner_s", "sparse, Horner s", ".1f"), ("now_s", "sparse, kept powers s", ".1f"),
                         ("gain_horner", "gain, Horner", ".2f"), ("gain", "gain", ".2f"),
                         ("difference", "branches differ by", ".1e")]))
    print(f"(continuation in omega, CPU time of the process, min of {args.repeats} interleaved repeats, the first "
          "orbit included; the difference: field values and leading multipliers' moduli, relative to the largest)")
    return C.finish("ring_sparse_steps", rows, args.repeats, t0)


if __name__ == "__main__":
    sys.exit(main())
