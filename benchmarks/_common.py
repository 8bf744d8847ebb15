"""Shared helpers of the benchmark scripts (not part of the package).

Every script measures *ratios* of methods run side by side in one process, with
the repeats interleaved (A, B, A, B, ...) and the minimum (or median) taken, and
prints the machine load: the benchmark machine is shared and noisy, so no lone
absolute time is meaningful. Results go to ``docs/benchmarks/<name>.json``.
"""

from __future__ import annotations

import argparse
import atexit
import ctypes
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Callable

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
OUT = ROOT / "docs" / "benchmarks"

#: Parameter order of the C baseline (benchmarks/rk4_blades.c).
C_PARAMS = "m kx ky cx cy F0 omega phi1 beta phi2 Delta alpha k mu kd".split()


def cpu_time() -> float:
    """CPU time of the calling thread (s): time given to other processes is not counted."""
    return time.thread_time()


def machine() -> dict:
    """Load and environment, for the record: with the CPU's model and the vector instructions Numba may compile for
    (the same code gives other rounding on another CPU, and other branches)."""
    import numba
    import scipy
    return {"loadavg_1_5_15": [round(x, 2) for x in os.getloadavg()], "cpus": os.cpu_count(),
            "python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__,
            "numba": numba.__version__, "machine": platform.machine(), "processor": platform.processor(),
            **_cpu(), "date": time.strftime("%Y-%m-%d %H:%M:%S")}


def _cpu() -> dict:
    """``cpu_model`` and ``cpu_flags`` (those of FMA and AVX that change a compiled kernel's rounding) from
    ``/proc/cpuinfo``, where there is one."""
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return {}
    fields = dict(line.split(":", 1) for line in text.splitlines() if ":" in line)
    fields = {k.strip(): v.strip() for k, v in fields.items()}
    flags = [f for f in fields.get("flags", "").split() if f in ("fma", "avx", "avx2", "avx512f")]
    return {"cpu_model": fields.get("model name", ""), "cpu_flags": " ".join(flags)}


def print_load(tag: str = "") -> list:
    la = [round(x, 2) for x in os.getloadavg()]
    print(f"[load average {la[0]} {la[1]} {la[2]} on {os.cpu_count()} cpus{' ' + tag if tag else ''}]", flush=True)
    return la


def write_json(name: str, data: dict) -> Path:
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / f"{name}.json"
    path.write_text(json.dumps(data, indent=1, default=_default) + "\n")
    return path


def start(doc: str) -> tuple:
    """A benchmark's command line (``--repeats``, default 2; its description the first line of ``doc``) and its
    start: the machine's load printed, ``(args, time.time())``."""
    ap = argparse.ArgumentParser(description=doc.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    print_load("at start")
    return args, time.time()


def ring_continuation(overrides: dict, opts: dict):
    """A continuation in ``omega`` of ``models/bladed_disk_24.yaml`` with the config ``overrides`` (strings, as
    ``--set`` takes them); ``opts``: ``start``, ``stop`` and :func:`~blademodel.orbits.continuation`'s keywords."""
    from blademodel.config import apply_overrides, load_config
    from blademodel.orbits import continuation
    cfg = apply_overrides(load_config(ROOT / "models" / "bladed_disk_24.yaml"), overrides)
    o = dict(opts)
    return continuation(cfg, "omega", o.pop("start"), o.pop("stop"), **o)


def same(a, b) -> float:
    """The largest difference of two branches' field values and leading multipliers' moduli, relative to the
    largest (inf where their points differ in number)."""
    if a.params.size != b.params.size:
        return np.inf
    ma, mb = np.abs(a.multipliers[:, 0]), np.abs(b.multipliers[:, 0])
    return max(float(np.max(np.abs(a.params - b.params)) / np.max(np.abs(a.params))),
               float(np.max(np.abs(ma - mb)) / np.max(ma)))


def finish(name: str, rows: list, repeats: int, t0: float, agree: float = 1e-7) -> int:
    """Write the ``rows`` of benchmark ``name`` (with the repeats, the machine and the time since ``t0``) to
    ``docs/benchmarks/<name>.json``; the exit code: 0 where every row's ``difference`` (of the two ways' branches)
    is within ``agree``."""
    result = {"benchmark": name, "repeats": repeats, "rows": rows, "machine": machine(),
              "elapsed_s": time.time() - t0}
    print(f"written {write_json(name, result)}")
    return 0 if all(r["difference"] <= agree for r in rows) else 1


def _default(o):
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(type(o))


def table(rows: list[dict], cols: list[tuple[str, str, str]]) -> str:
    """Plain-text table; ``cols`` = (key, header, format)."""
    cells = [[h for _, h, _ in cols]]
    for r in rows:
        cells.append([("-" if r.get(k) is None else format(r[k], f)) if f else str(r.get(k, "-"))
                      for k, _, f in cols])
    w = [max(len(c[i]) for c in cells) for i in range(len(cols))]
    lines = ["  ".join(c.rjust(w[i]) if i else c.ljust(w[i]) for i, c in enumerate(row)) for row in cells]
    lines.insert(1, "  ".join("-" * x for x in w))
    return "\n".join(lines)


def scale_vector(cfg, n: int) -> np.ndarray:
    """Per-state scale of the error norm: ``gap`` for displacements and the Jenkins
    stretch, ``gap * omega`` for velocities (the paper's X = x/gap, X' = v/(gap omega))."""
    s = np.full(n, abs(cfg.gap))
    s[4:8] = abs(cfg.gap) * cfg.omega
    return s


def state_error(y, y_ref, scale) -> float:
    """Max-norm of the scaled final-state difference (non-dimensional, as X = x/gap)."""
    return float(np.max(np.abs(np.asarray(y)[: len(scale)] - np.asarray(y_ref)[: len(scale)]) / scale))


# --------------------------------------------------------------------------- C baseline

class CKernel:
    """The hand-written C RK4 (benchmarks/rk4_blades.c), compiled with ``gcc -O3``."""

    def __init__(self, flags=("-O3",)):
        build_dir = Path(tempfile.mkdtemp(prefix="blademodel-bench-"))
        atexit.register(shutil.rmtree, build_dir, ignore_errors=True)
        src = HERE / "rk4_blades.c"
        lib = build_dir / "rk4_blades.so"
        cmd = ["gcc", *flags, "-shared", "-fPIC", "-o", str(lib), str(src), "-lm"]
        subprocess.run(cmd, check=True)
        self.command = " ".join(cmd[:-4] + ["rk4_blades.c", "-lm"])
        self.lib = ctypes.CDLL(str(lib))
        dp, lp = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_long)
        f = self.lib.integrate
        f.argtypes = [ctypes.c_int, dp, ctypes.POINTER(ctypes.c_int), dp, ctypes.c_double, ctypes.c_long,
                      ctypes.c_long, ctypes.c_long, ctypes.c_double, ctypes.c_long, lp, dp, dp]
        f.restype = ctypes.c_int
        self._f, self._dp, self._lp = f, dp, lp

    def run(self, cfg, model, y0, mode0: int, period: float, steps: int, start: int, end: int,
            event_tol: float = 1e-10, max_events: int = 100):
        """Integrate periods ``[start, end)``; returns ``(status, y, mode, counters[steps, events, location_substeps, rhs])``."""
        law = {"coulomb": 0, "bilinear": 1}[cfg.friction]
        prm = np.array([model.parameters.get(n, 1.0) for n in C_PARAMS], dtype=float)
        y = np.array(y0, dtype=float)
        mode = ctypes.c_int(int(mode0))
        c = np.zeros(4, dtype=np.int64)
        po = np.empty((end - start, y.size))
        t = ctypes.c_double()
        dp = self._dp
        st = self._f(law, y.ctypes.data_as(dp), ctypes.byref(mode), prm.ctypes.data_as(dp), period, steps,
                     start, end, event_tol, max_events, c.ctypes.data_as(self._lp), po.ctypes.data_as(dp),
                     ctypes.byref(t))
        return st, y, mode.value, c


def kernel_runner(integ, y0, mode0: int, start: int, end: int):
    """A closure running the compiled kernel over periods ``[start, end)`` from a copy of ``y0``."""
    from blademodel.numeric.contract import N_COUNTERS
    n = integ.n_state
    po = np.empty((end - start, n))

    def run():
        y = np.array(y0, dtype=float)
        c = np.zeros(N_COUNTERS, dtype=np.int64)
        st, mode, _ = integ.advance(y, mode0, start, end, poincare=po, counters=c)
        return st, y, mode, c
    return run


def clocks(f):
    """``(result, wall s, process CPU s)`` of ``f()``."""
    w, c = time.perf_counter(), time.process_time()
    out = f()
    return out, time.perf_counter() - w, time.process_time() - c


def ring_state(cfg, steps: int, periods: int = 50):
    """A ring's integrator, its state after ``periods`` from rest (physical states), mode and state scale."""
    from blademodel.numeric.kernels import make_integrator
    ig = make_integrator(cfg.build(), steps_per_period=steps)
    y = ig.initial_state()
    status, mode, _ = ig.advance(y, ig.mode_of(y), 0, periods)
    assert status == 0
    y = y[:ig.n_physical].copy()
    return ig, y, mode, np.maximum(np.abs(y), 1e-3 * np.abs(y).max())


def interleaved(funcs: dict, repeats: int, clock=cpu_time) -> dict:
    """Time each callable ``repeats`` times, interleaved; returns ``{name: [times]}``."""
    times = {k: [] for k in funcs}
    for _ in range(repeats):
        for k, f in funcs.items():
            t0 = clock()
            f()
            times[k].append(clock() - t0)
    return times


def compare_ways(ways: dict, run: Callable, repeats: int) -> tuple[dict, dict]:
    """``run()`` after each of ``ways`` (name: a function that sets that way up), ``repeats`` times interleaved,
    CPU time of the process (BLAS threads included): the least time and the last result of each way."""
    results = {}

    def timed(way):
        ways[way]()
        results[way] = run()

    times = interleaved({w: (lambda w=w: timed(w)) for w in ways}, repeats, clock=time.process_time)
    return {w: min(t) for w, t in times.items()}, results


def python_env(**extra) -> dict:
    env = dict(os.environ)
    env.update({k: str(v) for k, v in extra.items()})
    env["PYTHONPATH"] = str(ROOT) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def run_python(code: str, **env) -> dict:
    """Run ``code`` in a fresh interpreter; it must print one JSON object last."""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=python_env(**env))
    if out.returncode:
        raise RuntimeError(f"subprocess failed:\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])
