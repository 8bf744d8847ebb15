"""Where do the pair's branches end? Continuation of both laws in each field over a wide range, both ways in omega.

Run from the repository root: ``python docs/tools/continuation_survey.py``. Prints, for each
branch, its points, its special points by kind and why it ended (about 1 min). The table in
``docs/continuation.md`` ("How far branches get") comes from it. With ``--scan`` it runs the omega
branches of both laws, both ways, at each longest step ``ds_max`` in :data:`SCAN` instead
(about 3 min): whether the branches get through at every step length. With ``--iwan`` it runs the
Iwan pair's branches (:data:`IWAN_JOBS`, about 4 min); with ``--elements 8`` instead, the omega branches both ways
of the pair with that many Iwan elements (:data:`ELEMENT_JOBS`, about 3 min at 8).
"""

from __future__ import annotations

import argparse
import time

from blademodel.orbits import continuation
from blademodel.zheng2022 import BladePair

#: (law, field, start, stop): omega both ways over 150 ... 600 rad/s (the paper's 290 inside), and each
#: of the paper's other parameters over the range its figures use or wider.
JOBS = [(law, "omega", 150.0, 600.0) for law in ("coulomb", "bilinear")] + \
       [(law, "omega", 600.0, 150.0) for law in ("coulomb", "bilinear")] + \
       [(law, f, a, b) for f, a, b in (("gamma", 0.5, 10.0), ("F0", 5.0, 120.0), ("gap", 1e-5, 2.5e-4),
                                       ("mu", 0.05, 1.0)) for law in ("coulomb", "bilinear")]
#: (field, start, stop, steps a period) of ``--iwan``: the Iwan pair, omega both ways at 1000 and 2000 steps a
#: period, F0 both ways, the other fields as above.
IWAN_JOBS = [("omega", 150.0, 600.0, 1000), ("omega", 600.0, 150.0, 1000), ("omega", 150.0, 600.0, 2000),
             ("omega", 600.0, 150.0, 2000), ("gamma", 0.5, 10.0, 1000), ("F0", 5.0, 120.0, 1000),
             ("F0", 60.0, 1.0, 1000), ("gap", 1e-5, 2.5e-4, 1000), ("mu", 0.05, 1.0, 1000)]
#: (field, start, stop, steps a period) of ``--elements N``: omega both ways for the pair with N Iwan elements.
ELEMENT_JOBS = [("omega", 150.0, 600.0, 1000), ("omega", 600.0, 150.0, 1000)]
#: The longest steps of ``--scan`` (the default is 0.05).
SCAN = (0.02, 0.03, 0.05, 0.07, 0.1, 0.15, 0.2, 0.3)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scan", action="store_true", help="the omega branches at every ds_max in SCAN")
    ap.add_argument("--iwan", action="store_true", help="the Iwan pair's branches (IWAN_JOBS)")
    ap.add_argument("--elements", type=int, default=None, metavar="N",
                    help="the branches of ELEMENT_JOBS for the pair with N Iwan elements (instead of IWAN_JOBS)")
    args = ap.parse_args()
    args.iwan = args.iwan or args.elements is not None
    jobs = [(law, f, a, b, None) for law, f, a, b in JOBS] if not args.scan else \
        [(law, "omega", a, b, d) for law in ("coulomb", "bilinear") for a, b in ((150.0, 600.0), (600.0, 150.0))
         for d in SCAN]
    if args.iwan:
        jobs = [("iwan", f, a, b, S) for f, a, b, S in (IWAN_JOBS if args.elements is None else ELEMENT_JOBS)]
    options = {} if args.elements is None else {"friction_options": {"elements": args.elements}}
    reached = 0
    for law, field, a, b, setting in jobs:
        t = time.process_time()
        steps = {} if setting is None else {"steps_per_period": setting} if args.iwan else {"ds_max": setting}
        br = continuation(BladePair(friction=law, **options), field, a, b, max_points=3000, workers=1, **steps)
        kinds = {}
        for p in br.special:
            kinds[p.kind] = kinds.get(p.kind, 0) + 1
        reached += br.message.startswith("reached")
        step = "" if setting is None else f" {setting:g} |"
        print(f"| {law} | {field} | {a:g} → {b:g} |{step} {len(br.params)} | "
              f"{', '.join(f'{v} {k}' for k, v in sorted(kinds.items())) or '-'} | {br.message} | "
              f"{time.process_time() - t:.0f} |", flush=True)
    print(f"{reached} of {len(jobs)} branches reached the end of their range")


if __name__ == "__main__":
    main()
