"""Work against accuracy of the stepping methods and event locations, side by side.

    python benchmarks/methods.py [--periods 50] [--repeats 3]

The paper's pair (Coulomb and bilinear, base case) over ``--periods`` periods from
rest, on its product-mode kernel: RK4 with bisection (the default), RK4 with
predicted event roots, RK8 with predicted roots, at a ladder of steps per period
each; ``event_tol = 1e-13`` so the location never limits the error. The error is
the final state's, in the paper's units (``X = x / gap``, ``X' = v / (gap omega)``),
against RK8 at ``S = 16000``. CPU times are thread times of interleaved repeats
(minimum). For each error level ``1e-4 ... 1e-11`` it prints the cheapest run of
each configuration reaching it and the cost ratios: what the higher order and the
predicted location buy. Writes ``docs/benchmarks/methods.json`` and ``.png``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402

from blademodel.zheng2022 import BladePair  # noqa: E402
from blademodel.numeric import make_integrator  # noqa: E402
from blademodel.numeric.contract import C_EVENTS, C_RHS, N_COUNTERS  # noqa: E402

TOL = 1e-13
CONFIGS = {"rk4 bisection": ("rk4", "bisection", (1000, 2000, 4000, 8000, 16000, 32000)),
           "rk4 predicted": ("rk4", "predicted", (1000, 2000, 4000, 8000, 16000, 32000)),
           "rk8 predicted": ("rk8", "predicted", (250, 350, 500, 700, 1000, 1400, 2000))}
LEVELS = [10.0 ** -k for k in range(4, 12)]


def runner(model, method, location, S, periods):
    integ = make_integrator(model, steps_per_period=S, event_tol=TOL, method=method, event_location=location)
    y0 = integ.initial_state()
    m0 = integ.mode_of(y0.copy())

    def run():
        y = y0.copy()
        c = np.zeros(N_COUNTERS, dtype=np.int64)
        st, _, _ = integ.advance(y, m0, 0, periods, counters=c)
        if st:
            raise RuntimeError(f"{method} {location} S={S}: status {st}")
        return y, c
    return run


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--periods", type=int, default=50)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    C.print_load("at start")
    out = {"benchmark": "methods", "periods": args.periods, "event_tol": TOL, "laws": {}}
    for law in ("coulomb", "bilinear"):
        cfg = BladePair(friction=law)
        model = cfg.build()
        ref, _ = runner(model, "rk8", "predicted", 16000, args.periods)()
        scale = C.scale_vector(cfg, len(ref))
        funcs, rows = {}, []
        for name, (method, loc, steps) in CONFIGS.items():
            for S in steps:
                f = runner(model, method, loc, S, args.periods)
                y, c = f()
                funcs[(name, S)] = f
                rows.append({"config": name, "S": S, "error": C.state_error(y, ref, scale),
                             "events": int(c[C_EVENTS]), "rhs": int(c[C_RHS])})
        times = C.interleaved(funcs, args.repeats)
        for r in rows:
            r["cpu_s"] = min(times[(r["config"], r["S"])])
        print(f"\n{law}: {args.periods} periods from rest, event_tol = {TOL:g} (CPU: min of {args.repeats})")
        print(C.table(rows, [("config", "config", ""), ("S", "S", "d"), ("error", "error", ".1e"),
                             ("events", "events", "d"), ("rhs", "RHS evals", "d"), ("cpu_s", "CPU s", ".4f")]))
        best = []
        for level in LEVELS:
            row = {"error <=": level}
            for name in CONFIGS:
                ok = [r for r in rows if r["config"] == name and r["error"] <= level]
                row[name] = min(r["cpu_s"] for r in ok) if ok else None
            b, p, h = row["rk4 bisection"], row["rk4 predicted"], row["rk8 predicted"]
            row["rk4 bis. / rk8"] = b / h if b and h else None
            row["rk4 pred. / rk8"] = p / h if p and h else None
            row["bisection / predicted (rk4)"] = b / p if b and p else None
            best.append(row)
        print(C.table(best, [("error <=", "error <=", ".0e"), ("rk4 bisection", "rk4 bis. s", ".4f"),
                             ("rk4 predicted", "rk4 pred. s", ".4f"), ("rk8 predicted", "rk8 pred. s", ".4f"),
                             ("rk4 bis. / rk8", "rk4 bis./rk8", ".2f"), ("rk4 pred. / rk8", "rk4 pred./rk8", ".2f"),
                             ("bisection / predicted (rk4)", "bis./pred.", ".2f")]))
        out["laws"][law] = {"runs": rows, "cheapest": best}
    out["machine"] = C.machine()
    path = C.write_json("methods", out)
    _plot(out, path.with_suffix(".png"))
    print(f"\nwrote {path} and {path.with_suffix('.png').name}")


def _plot(out, png):
    import matplotlib
    import matplotlib.ticker
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, (law, d) in zip(axes, out["laws"].items()):
        for name in CONFIGS:
            rs = [r for r in d["runs"] if r["config"] == name]
            ax.loglog([r["cpu_s"] for r in rs], [max(r["error"], 1e-16) for r in rs], "o-", label=name)
        ax.set_title(f"{law} pair, {out['periods']} periods")
        ax.set_xlabel("CPU time (s)")
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("final-state error (units of the gap)")
    axes[0].legend()
    fig.tight_layout()
    fig.savefig(png, dpi=110)


if __name__ == "__main__":
    main()
