"""A tuned ring's period-doubled branch on the reduced map against the whole ring's period-2 map.

    python benchmarks/ring_doubling.py [--points 8] [--repeats 2]

The tuned 96-blade Coulomb ring of ``models/bladed_disk_24.yaml`` at engine order 12
(``S = 600`` steps a period: the reduced map covers ``T / 8``) has a period doubling near
272.27 rad/s where the reduced map has a branch point. The doubling is found once on the
reduced map (not timed); then ``period_doubled_branch`` follows the doubled branch for
``--points`` points with ``cyclic=True`` (on the reduced map) and without (on the whole
ring's period-2 map), one thread, the two interleaved ``--repeats`` times, the least CPU
thread time of each taken. Printed side by side: points, integrations (of ``T / 8`` and of
``2 T``), replays, the last value of the field, and the ratio of the times; the two
branches are checked to take the same values of the field (to ``1e-6``).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parent))
import _common as C  # noqa: E402

from blademodel.config import apply_overrides, load_config  # noqa: E402
from blademodel.orbits import continuation, period_doubled_branch  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--points", type=int, default=8)
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    C.print_load("start")
    cfg = apply_overrides(load_config(C.ROOT / "models" / "bladed_disk_24.yaml"),
                          {"blades": "96", "engine_order": "12"})
    b = continuation(cfg, "omega", 272.0, 272.6, workers=1, cyclic=True, steps_per_period=600)
    (pd,) = b.points("period-doubling")
    out = {}

    def doubled(cyclic):
        out[cyclic] = period_doubled_branch(cfg, "omega", pd, 271.5, 273.0, steps_per_period=600, workers=1,
                                            max_points=args.points, cyclic=cyclic)

    times = C.interleaved({False: lambda: doubled(False), True: lambda: doubled(True)}, args.repeats)
    whole, cyc = out[False], out[True]
    same = whole.params.size == cyc.params.size and np.allclose(whole.params, cyc.params, rtol=0, atol=1e-6)
    print(f"tuned 96-blade Coulomb ring, EO 12, S = 600: the period-doubled branch from {pd.param:.6f} rad/s, "
          f"{args.points} points, one thread (CPU thread time, least of {args.repeats} interleaved)")
    rows = [{"map": label, "points": x.params.size, "integrations": x.integrations, "replays": x.replays,
             "cpu": min(times[cyclic]), "last": float(x.params[-1]), "ended": x.message}
            for label, x, cyclic in (("whole period-2 map", whole, False), ("reduced (T / 8)", cyc, True))]
    print(C.table(rows, [("map", "map", ""), ("points", "points", "d"), ("integrations", "integrations", "d"),
                         ("replays", "replays", "d"), ("cpu", "CPU s", ".1f"), ("last", "last omega", ".7f"),
                         ("ended", "ended", "")]))
    C.write_json("ring_doubling", {"machine": C.machine(), "doubling": pd.param, "points": args.points,
                                   "times": {"whole": times[False], "reduced": times[True]}, "rows": rows,
                                   "same_values": bool(same)})
    print(f"whole / reduced CPU time: {min(times[False]) / min(times[True]):.2f} "
          f"(each repeat: {', '.join(f'{a / b:.2f}' for a, b in zip(times[False], times[True]))})")
    print(f"the same values of the field: {same}")
    C.print_load("end")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
