"""Where do the pair's branches end? Continuation of both laws in each field over a wide range, both ways in omega.

Run from the repository root: ``python docs/tools/continuation_survey.py``. Prints, for each
branch, its points, its special points by kind and why it ended (about 2 min). The table in
``docs/orbits.md`` ("How far branches get") comes from it.
"""

from __future__ import annotations

import time

from blademodel.orbits import continuation
from blademodel.zheng2022 import BladePair

#: (law, field, start, stop): omega both ways over 150 ... 600 rad/s (the paper's 290 inside), and each
#: of the paper's other parameters over the range its figures use or wider.
JOBS = [(law, "omega", 150.0, 600.0) for law in ("coulomb", "bilinear")] + \
       [(law, "omega", 600.0, 150.0) for law in ("coulomb", "bilinear")] + \
       [(law, f, a, b) for f, a, b in (("gamma", 0.5, 10.0), ("F0", 5.0, 120.0), ("gap", 1e-5, 2.5e-4),
                                       ("mu", 0.05, 1.0)) for law in ("coulomb", "bilinear")]


def main():
    reached = 0
    for law, field, a, b in JOBS:
        t = time.process_time()
        br = continuation(BladePair(friction=law), field, a, b, max_points=3000, workers=1)
        kinds = {}
        for p in br.special:
            kinds[p.kind] = kinds.get(p.kind, 0) + 1
        reached += br.message.startswith("reached")
        print(f"| {law} | {field} | {a:g} → {b:g} | {len(br.params)} | "
              f"{', '.join(f'{v} {k}' for k, v in sorted(kinds.items())) or '-'} | {br.message} | "
              f"{time.process_time() - t:.0f} |", flush=True)
    print(f"{reached} of {len(JOBS)} branches reached the end of their range")


if __name__ == "__main__":
    main()
