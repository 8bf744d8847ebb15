"""Start-up cost: a fresh process's first simulation, with an empty and with a warm cache.

    python benchmarks/startup.py

Each run is a new interpreter that imports blademodel,
builds the paper's pair (Coulomb, defaults), sets up the kernel and runs a short
simulation (``simulate(model, transient=50, periods=50)``). Run 1 uses an empty
``BLADEMODEL_CACHE_DIR`` (symbolic derivation, code generation, Numba compilation);
runs 2 and 3 reuse it. Phases:

* import: ``import blademodel.config, blademodel.numeric``;
* kernel: ``HybridIntegrator(model)`` (generate or load the generated module, which
  imports Numba; stability check), then the first call of each entry point
  (``initial_mode`` through ``mode_of``, ``integrate`` over zero periods): Numba
  compiles it, or loads it from its cache;
* run: the short simulation itself.

Where the time goes is measured in a 4th run under ``-X importtime`` (self time
summed per top-level package over the whole process) and Numba's per-dispatcher cache
statistics; two floors are measured the same way: a bare interpreter
(``python -c pass``) and a trivial ``@njit(cache=True)`` function loaded from its
cache in a fresh process (what any Numba-cached kernel costs to start here).
The issue asks for a second process to start in under a second.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402

PROBE = r"""
import time, sys, json
w0 = time.time()
t0 = time.perf_counter()
import blademodel.config, blademodel.numeric
from blademodel.zheng2022 import BladePair
from blademodel.numeric import HybridIntegrator, simulate
t1 = time.perf_counter()
mods1 = {m for m in ("sympy", "scipy", "scipy.linalg", "scipy.integrate", "numba", "matplotlib", "xarray") if m in sys.modules}
model = BladePair().build()
integ = HybridIntegrator(model)
t2 = time.perf_counter()
y = integ.initial_state(); m = integ.mode_of(y)
t3 = time.perf_counter()
integ.advance(y, m, 0, 0)
t4 = time.perf_counter()
r = simulate(model, transient=50, periods=50)
t5 = time.perf_counter()
mods = {m for m in ("sympy", "scipy", "scipy.linalg", "scipy.integrate", "numba", "matplotlib", "xarray") if m in sys.modules}
stats = {}
for name in ("rhs", "guards", "transition", "rk4_step", "crossed", "first_crossing", "initial_mode", "integrate"):
    d = getattr(integ.module, name)
    s = d.stats
    stats[name] = {"cache_hits": sum(s.cache_hits.values()), "cache_misses": sum(s.cache_misses.values()),
                   "compiled": len(d.overloads)}
print(json.dumps({"wall_start": w0, "wall_ready": time.time(), "import": t1 - t0, "generate_or_load": t2 - t1, "first_initial_mode": t3 - t2,
                  "first_integrate": t4 - t3, "run": t5 - t4, "in_process": t5 - t0,
                  "modules_after_import": sorted(mods1), "modules_at_end": sorted(mods), "dispatchers": stats,
                  "steps": r.counters["steps"]}))
"""

NUMBA_FLOOR = r"""
import time, json
w0 = time.time()
t0 = time.perf_counter()
import numpy as np
from numba import njit
@njit(cache=True)
def f(x):
    return x[0] + 1.0
f(np.zeros(2))
print(json.dumps({"in_process": time.perf_counter() - t0, "wall_start": w0, "wall_ready": time.time()}))
"""


def run(code: str, cache: str | None = None, importtime: bool = False) -> dict:
    env = C.python_env(**({"BLADEMODEL_CACHE_DIR": cache} if cache else {}))
    t0, w0 = time.perf_counter(), time.time()
    cmd = [sys.executable, *(["-X", "importtime"] if importtime else []), "-c", code]
    out = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall, w1 = time.perf_counter() - t0, time.time()
    if out.returncode:
        raise RuntimeError(out.stderr[-3000:])
    res = json.loads(out.stdout.strip().splitlines()[-1])
    res["process_wall"] = wall
    res["interpreter_start"] = res["wall_start"] - w0
    res["to_result"] = res["wall_ready"] - w0  # launch until the simulation's result is there
    res["exit"] = w1 - res["wall_ready"]
    res["imports_by_package"] = _importtime(out.stderr)
    return res


def _importtime(stderr: str) -> dict:
    """Self import time (s) per top-level package."""
    agg = defaultdict(float)
    for line in stderr.splitlines():
        parts = line.split("|")
        if not line.startswith("import time:") or len(parts) != 3:
            continue
        try:
            self_us = int(parts[0].split(":")[1])
        except ValueError:  # the header line
            continue
        agg[parts[2].strip().split(".")[0]] += self_us * 1e-6
    return dict(sorted(agg.items(), key=lambda kv: -kv[1]))


def main():
    t_start = time.time()
    C.print_load("at start")
    with tempfile.TemporaryDirectory(prefix="bm_startup_") as cache:
        runs = [run(PROBE, cache) for _ in range(3)]
        traced = run(PROBE, cache, importtime=True)  # a 4th run, for the import breakdown only
    with tempfile.TemporaryDirectory(prefix="bm_numba_floor_") as d:
        src = Path(d) / "floor.py"  # Numba caches next to the source file
        src.write_text(NUMBA_FLOOR)
        floor = [_run_file(src) for _ in range(3)]
    bare = []
    for _ in range(3):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", "pass"], check=True)
        bare.append(time.perf_counter() - t0)
    la = C.print_load("at end")

    phases = ["interpreter_start", "import", "generate_or_load", "first_initial_mode", "first_integrate", "run"]
    labels = {"interpreter_start": "interpreter start (python itself)", "import": "import blademodel", "generate_or_load": "HybridIntegrator() (generate / load module)",
              "first_initial_mode": "first call initial_mode (compile / cache load)",
              "first_integrate": "first call integrate (compile / cache load)", "run": "simulate 100 periods"}
    labels.update(to_result="launch -> result (start-up + run)", exit="process exit (after the result)",
                  process_wall="process wall time")
    rows = []
    for ph in phases + ["to_result", "exit", "process_wall"]:
        row = {"phase": labels[ph]}
        for i, r in enumerate(runs):
            row[f"r{i}"] = r[ph]
        row["share2"] = runs[1][ph] / runs[1]["to_result"]
        rows.append(row)
    print("\nStart-up of a fresh process (s; shared machine, see the load; the split is what matters)")
    print(C.table(rows, [("phase", "phase", ""), ("r0", "1st run (empty cache)", ".2f"),
                         ("r1", "2nd run (cache)", ".2f"), ("r2", "3rd run (cache)", ".2f"),
                         ("share2", "share of 2nd (to result)", ".0%")]))
    second = min(runs[1]["to_result"], runs[2]["to_result"])
    imp = traced["imports_by_package"]
    top = list(imp.items())[:8]
    print("\nrun with the cache under -X importtime, self import time by package (all imports of the process, "
          "also those Numba makes when it loads its first cached function):")
    print("  " + ", ".join(f"{k} {v:.2f}" for k, v in top) + f"; all imports {sum(imp.values()):.2f} s")
    print(f"modules loaded after 'import blademodel': {runs[1]['modules_after_import']}; at the end: "
          f"{runs[1]['modules_at_end']}")
    print("dispatchers (2nd run): " + ", ".join(f"{k}: {'cache' if v['cache_hits'] else 'compiled' if v['compiled'] else 'unused'}"
                                              for k, v in runs[1]["dispatchers"].items()))
    fl = min(f["to_result"] for f in floor)
    print(f"\nfloors, fresh process, launch to result: bare interpreter (whole process) {min(bare):.2f} s; a trivial "
          f"@njit(cache=True) function from its cache {fl:.2f} s (numba import, its target registries, which import "
          "scipy.linalg for numba's BLAS check, the cache load)")
    ratio_first = runs[0]["to_result"] / second
    print(f"\n2nd process, launch to result: {second:.2f} s ({second - fl:.2f} s above the Numba floor, "
          f"{ratio_first:.0f} x faster than the 1st run); goal < 1 s: {'MET' if second < 1.0 else 'MISSED'}")
    out = {"benchmark": "startup", "runs": runs, "importtime_run": traced, "numba_floor": floor, "bare_interpreter_s": bare,
           "second_process_s": second, "goal_met": second < 1.0, "machine": C.machine(), "load_end": la,
           "elapsed_s": time.time() - t_start}
    path = C.write_json("startup", out)
    plot(runs, fl, min(bare), path.with_suffix(".png"))
    print(f"\nwrote {path} and {path.with_suffix('.png').name}  ({time.time() - t_start:.0f} s)")


def _run_file(src: Path) -> dict:
    t0, w0 = time.perf_counter(), time.time()
    out = subprocess.run([sys.executable, str(src)], capture_output=True, text=True, env=C.python_env())
    wall = time.perf_counter() - t0
    if out.returncode:
        raise RuntimeError(out.stderr[-2000:])
    res = json.loads(out.stdout.strip().splitlines()[-1])
    res["process_wall"] = wall
    res["to_result"] = res["wall_ready"] - w0
    return res


def plot(runs, floor, bare, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.2), gridspec_kw={"width_ratios": [1, 1.3]})
    phases = ["interpreter_start", "import", "generate_or_load", "first_initial_mode", "first_integrate", "run"]
    names = ["interpreter", "import blademodel", "HybridIntegrator()", "1st initial_mode", "1st integrate", "run"]
    cols = ["C7", "C0", "C1", "C2", "C3", "C4"]
    for ax, i, title in ((axes[0], 0, "1st run (empty cache)"), (axes[1], 1, "2nd run (cache) and floors")):
        left = 0.0
        for ph, nm, col in zip(phases, names, cols):
            ax.barh(0, runs[i][ph], left=left, color=col, label=nm)
            left += runs[i][ph]
        ax.set_yticks([0], [title.split(" (")[0]])
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("seconds, launch to result")
    ax = axes[1]
    ax.barh(1, floor, color="0.6")
    ax.barh(2, bare, color="0.85")
    ax.set_yticks([0, 1, 2], ["2nd run", "numba floor", "python -c pass"])
    ax.axvline(1.0, color="r", ls="--", lw=0.8, label="goal 1 s")
    ax.invert_yaxis()
    axes[0].legend(fontsize=7, loc="upper right")
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
