"""A tuned bladed disk's FRF by continuation on the whole period's map and on the cyclic reduction.

    python benchmarks/ring_cyclic.py [--blades 24] [--start 270] [--stop 300] [--repeats 2]

Tuned Coulomb rings of ``models/bladed_disk_24.yaml`` (engine order 3, 1000 steps a
period: the reduced map covers ``T / 8``), continued in omega over ``[start, stop]``
with ``continuation(..., cyclic=False)`` and ``cyclic=True``, one thread, the two
interleaved ``--repeats`` times, the least CPU thread time of each taken. Printed side by
side: points, integrations and replays of each branch (the reduced map's integrations
cover ``T / 8``), its special points, and the ratio of the times. The two branches are
checked to have the same border collisions and Neimark-Sacker points (to ``1e-5`` of the
field) and the same distinct grazing points (to ``1e-3``).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parent))
import _common as C  # noqa: E402

from blademodel.config import apply_overrides, load_config  # noqa: E402
from blademodel.orbits import continuation  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--blades", type=int, default=24)
    ap.add_argument("--start", type=float, default=270.0)
    ap.add_argument("--stop", type=float, default=300.0)
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    C.print_load("start")
    cfg = apply_overrides(load_config(C.ROOT / "models" / "bladed_disk_24.yaml"), {"blades": str(args.blades)})
    continuation(cfg, "omega", args.start, args.start + 0.05, workers=1, max_points=3)   # compile, warm caches
    out = {}

    def branch(cyclic):
        out[cyclic] = continuation(cfg, "omega", args.start, args.stop, workers=1, cyclic=cyclic, max_points=2000)

    times = C.interleaved({False: lambda: branch(False), True: lambda: branch(True)}, args.repeats)
    whole, cyc = out[False], out[True]

    def bifurcations(b):
        return [(q.kind, q.param) for q in b.special if q.kind in ("border-collision", "neimark-sacker",
                                                                    "period-doubling", "fold")]

    def grazings(b):
        g = np.sort([q.param for q in b.special if q.kind == "grazing"])
        return g[np.append(True, np.diff(g) > 1e-3)] if g.size else g

    same = ([k for k, _ in bifurcations(whole)] == [k for k, _ in bifurcations(cyc)]
            and np.allclose([v for _, v in bifurcations(whole)], [v for _, v in bifurcations(cyc)], rtol=0,
                            atol=1e-5))
    gw, gc = grazings(whole), grazings(cyc)
    same_g = gw.size == gc.size and np.allclose(gw, gc, rtol=0, atol=1e-3)
    print(f"tuned {args.blades}-blade Coulomb ring, omega = {args.start:g} ... {args.stop:g} rad/s, one thread "
          f"(CPU thread time, least of {args.repeats} interleaved)")
    rows = []
    for label, b, cyclic in (("whole period", whole, False), ("cyclic (T / 8)", cyc, True)):
        rows.append({"map": label, "points": b.params.size, "integrations": b.integrations, "replays": b.replays,
                     "cpu": min(times[cyclic]), "bif": ", ".join(f"{k} {v:.6f}" for k, v in bifurcations(b)),
                     "grazing": grazings(b).size, "ended": b.message})
    print(C.table(rows, [("map", "map", ""), ("points", "points", "d"), ("integrations", "integrations", "d"),
                         ("replays", "replays", "d"), ("cpu", "CPU s", ".1f"), ("bif", "bifurcations", ""),
                         ("grazing", "grazing points (distinct)", "d"), ("ended", "ended", "")]))
    C.write_json("ring_cyclic", {"machine": C.machine(), "blades": args.blades, "range": [args.start, args.stop],
                                 "times": {"whole": times[False], "cyclic": times[True]}, "rows": rows,
                                 "same_bifurcations": same, "same_grazing": same_g})
    print(f"whole / cyclic CPU time: {min(times[False]) / min(times[True]):.2f} "
          f"(each repeat: {', '.join(f'{a / b:.2f}' for a, b in zip(times[False], times[True]))})")
    print(f"the same bifurcations: {same}; the same distinct grazing points: {same_g}")
    C.print_load("end")
    return 0 if same and same_g else 1


if __name__ == "__main__":
    sys.exit(main())
