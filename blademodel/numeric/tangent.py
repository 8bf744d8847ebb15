"""Sensitivities of the product-mode kernel's flow: monodromy and parameter derivatives.

:func:`flow_sensitivity` integrates whole periods with the kernel, logging its
events, then repeats the run from the log with the tangent carried along
(:mod:`.tangent_loop`): the exact derivative of every Runge-Kutta step and the
saltation matrix of every event. It returns the state, ``d y(nT) / d y(0)``
(the monodromy matrix over ``n`` periods) and, for a direction in the raw
parameters, ``d y(nT) / d lambda``.

The derivative code is generated and compiled on first use per model structure
(:mod:`.sensitivity_codegen`, :mod:`.tangent_loop`) into its own module beside the
kernel's, so simulations never build it.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from types import ModuleType

import numpy as np

from .compiled import _load, cache_dir, derive_cached, hash_sources, PACKAGE
from .contract import C_LOGGED, N_COUNTERS, STATUS_NAMES
from .methods import get_method

_TEMPLATE_FUNCTIONS = ("flow_jacobian", "flow_partials", "guard_gradient", "reset_jacobian", "tangent_step",
                       "tangent_sum", "power_apply", "queue_whole_steps", "step_tangent", "event_time_tangent",
                       "reset_tangent", "skip_to", "kernel_step", "same_state", "affine_jacobian", "replay_tangent")


#: How the functions of a tangent module are compiled (:mod:`.code_libraries`): the replay is an entry point
#: called from Python only, ``reset_jacobian`` is called from Python and from the replay (Numba's own
#: pipeline); the others are only linked into the replay (no wrappers, no machine code of their own).
#: Only the functions called from Python are cached: the others' code is cached inside the replay's.
_TANGENT_PIPELINES = {"replay_tangent": "cache=True, pipeline_class=EntryPointCompiler", "reset_jacobian": "cache=True"}
_LINKED_ONLY = "no_cpython_wrapper=True, no_cfunc_wrapper=True, pipeline_class=LinkedOnlyCompiler"


class SensitivityError(RuntimeError):
    """The tangent integration could not follow the kernel's run (status and time in the message)."""


@dataclass
class FlowSensitivity:
    """The state after whole periods and its derivatives.

    Attributes
    ----------
    state : ndarray
        Physical states at the end (the kernel's own result).
    mode : int
        The mode at the end.
    monodromy : ndarray
        ``d state / d y0`` (physical states by physical states).
    parameter : ndarray or None
        ``d state / d lambda`` along the given parameter direction, period change included.
    events : int
        Events crossed (each one's saltation matrix applied).
    """

    state: np.ndarray
    mode: int
    monodromy: np.ndarray
    parameter: np.ndarray | None
    events: int


_MODULES: dict = {}


def sensitivity_module(integrator) -> ModuleType:
    """The compiled sensitivity module of a product-mode integrator's model (built once per structure)."""
    compiled = integrator.compiled
    if compiled.path in _MODULES:
        return _MODULES[compiled.path]
    here = PACKAGE / "numeric"
    key = hash_sources([compiled.path, here / "sensitivity_codegen.py", here / "tangent_loop.py",
                        here / "contract.py", here / "tangent.py", here / "code_libraries.py"])
    path = cache_dir() / f"t_{compiled.path.stem}_{key}.py"
    if not path.exists():
        import inspect

        from . import tangent_loop
        from .sensitivity_codegen import sensitivity_source
        system = derive_cached(integrator.model)
        L = ["import math", "import sys as _sys", "import numpy as np", "from numba import njit", "",
             "# the kernel's functions and tables, compiled (or loaded) once for the kernel itself",
             f"_kernel = _sys.modules[{integrator.module.__name__!r}]",
             "globals().update({_n: getattr(_kernel, _n) for _n in dir(_kernel) if not _n.startswith('__')})",
             "", "# ---- derivatives (blademodel/numeric/sensitivity_codegen.py) ----",
             sensitivity_source(system), "# ---- tangent replay (blademodel/numeric/tangent_loop.py) ----",
             inspect.getsource(tangent_loop), ""]
        L += ["from blademodel.numeric.code_libraries import EntryPointCompiler, LinkedOnlyCompiler", ""]
        L += [f"{fn} = njit({_TANGENT_PIPELINES.get(fn, _LINKED_ONLY)})({fn})" for fn in _TEMPLATE_FUNCTIONS]
        tmp = path.with_suffix(f".tmp{os.getpid()}")
        tmp.write_text("\n".join(L) + "\n")
        os.replace(tmp, path)
    _MODULES[compiled.path] = _load(path)
    return _MODULES[compiled.path]


_RK4_TABLEAU = get_method("rk4").tableau()
_NO_RECORD = np.zeros((0, 1))


def _tableau(integrator) -> np.ndarray:
    """The integrator's method as a tableau (its fused classical RK4 as RK4's)."""
    return integrator._tableau if integrator._tableau.size else _RK4_TABLEAU


def logged_run(integrator, y, mode, periods: int = 1, log_size: int = 256):
    """Integrate ``periods`` periods from ``(y, mode)`` at ``t = 0`` with the kernel, logging every event.

    Returns ``(end, mode_end, log, n_log)``: the full end state, the end mode, the
    event log (``integrator.log_buffer``, grown until the run fits) and its length: what
    :func:`flow_sensitivity` replays.

    Raises
    ------
    SensitivityError
        If the kernel stopped early.
    """
    n = integrator.n_physical
    start = np.zeros(integrator.n_state)
    start[:n] = np.asarray(y, dtype=float)[:n]
    size = max(int(log_size), 16)
    while True:
        counters = np.zeros(N_COUNTERS, dtype=np.int64)
        log = integrator.log_buffer(size)
        end = start.copy()
        status, mode_end, t = integrator.advance(end, int(mode), 0, int(periods), log=log, counters=counters)
        if status != 0:
            raise SensitivityError(f"the integration stopped at t = {t:.6g} s: {STATUS_NAMES.get(status, status)}")
        if counters[C_LOGGED] <= size:
            return end, int(mode_end), log, int(counters[C_LOGGED])
        size = int(counters[C_LOGGED]) + 16


def flow_sensitivity(integrator, y, mode: int, periods: int = 1, *, dp=None, dperiod: float = 0.0,
                     log_size: int = 256, run: tuple | None = None, record=None) -> FlowSensitivity:
    """Integrate ``periods`` excitation periods from ``(y, mode)`` at ``t = 0`` with the state's derivatives.

    Parameters
    ----------
    integrator : HybridIntegrator
        A product-mode integrator (:func:`~blademodel.numeric.kernels.make_integrator`).
    y : array_like
        Physical start state (the accumulators, if any, start at zero).
    mode : int
        Start mode (as the kernel takes it: no guard is fired at ``t = 0``).
    periods : int
        Whole periods.
    dp : array_like, optional
        A direction in the raw parameters (``integrator.meta["params"]``): the result's
        ``parameter`` is the derivative along it.
    dperiod : float
        How fast the excitation period changes along ``dp`` (for a frequency: the final
        time moves, and the state with it at its rate ``f``).
    log_size : int
        First size of the event log (doubled until the run fits).
    run : tuple, optional
        The kernel's run from ``(y, mode)`` already made, as :func:`logged_run` returns
        it: only the replay is done.
    record : ndarray, optional
        That run's full states at every step (``record_buffer``'s ``y``, the start in
        row 0): the replay reads the state of whole steps from it instead of stepping
        it again.

    Returns
    -------
    FlowSensitivity

    Raises
    ------
    SensitivityError
        If the kernel stopped early, or the replay could not follow its events
        (a grazing event: an event guard with zero rate along the flow).
    """
    if getattr(integrator, "kernel", "") != "product":
        raise SensitivityError("sensitivities are available for the product-mode kernel only "
                               "(models with at most one contact)")
    mod = sensitivity_module(integrator)
    n = integrator.n_physical
    start = np.zeros(integrator.n_state)
    start[:n] = np.asarray(y, dtype=float)[:n]
    end, mode_end, log, n_log = logged_run(integrator, start, mode, periods, log_size) if run is None else run
    npar = int(mod.N_RAW_PARAMS)
    use_p = dp is not None
    dpv = np.zeros(npar) if dp is None else np.asarray(dp, dtype=float)
    if dpv.shape != (npar,):
        raise ValueError(f"dp must have one entry per raw parameter ({npar}: "
                         f"{', '.join(integrator.meta['params'])}), got shape {dpv.shape}")
    V = np.zeros((n, n + 1 if use_p else n))
    V[:, :n] = np.eye(n)
    yr = start.copy()
    status, mode_r, t = mod.replay_tangent(yr, int(mode), integrator.p, integrator.period,
                                           integrator.steps_per_period, 0, int(periods), _tableau(integrator),
                                           integrator._tableau, *log, n_log, V, use_p, dpv, float(dperiod),
                                           _NO_RECORD if record is None else record)
    if status != 0:
        raise SensitivityError(f"the tangent replay stopped at t = {t:.6g} s: {STATUS_NAMES.get(status, status)}")
    if mode_r != mode_end:
        raise SensitivityError(f"the tangent replay ended in mode {mode_r}, the kernel in {mode_end}")
    # the replay takes the logged transitions, but a reset that chooses among internal states
    # (which Iwan elements slip) decides on its own state: it must end where the kernel did
    gap = np.abs(yr[:n] - end[:n])
    allowed = 1e-7 * np.maximum(np.abs(start[:n]), np.abs(end[:n])) + 1e-9 * np.max(np.abs(end[:n]))
    if np.any(gap > allowed):
        i = int(np.argmax(gap / np.maximum(allowed, 1e-300)))
        raise SensitivityError(f"the tangent replay left the kernel's trajectory (state "
                               f"{integrator.meta['state'][i]}: {yr[i]:.9g} against {end[i]:.9g})")
    dlam = V[:, n].copy() if use_p else None
    return FlowSensitivity(state=end[:n].copy(), mode=int(mode_end), monodromy=V[:, :n].copy(), parameter=dlam,
                           events=n_log)


def settle_jacobian(integrator, fired: list, dp=None) -> tuple[np.ndarray, np.ndarray]:
    """``d y / d y0`` and ``d y / d lambda`` of the resets fired at ``t = 0`` (:func:`~blademodel.orbits.period_map.settle`).

    A start state past a guard takes that guard's transition at once, at the fixed
    time 0: only its reset is differentiated (no event time moves).
    """
    mod = sensitivity_module(integrator)
    n = integrator.n_physical
    npar = int(mod.N_RAW_PARAMS)
    dpv = np.zeros(npar) if dp is None else np.asarray(dp, dtype=float)
    D = np.eye(n)
    dl = np.zeros(n)
    Ry, Rp, Rt = np.empty((n, n)), np.empty((n, npar)), np.empty(n)
    for mode, gi, target, before in fired:
        Ry[:] = np.eye(n)
        Rp[:] = 0.0
        Rt[:] = 0.0
        if not mod.reset_jacobian(int(mode), int(gi), int(target), 0.0, before, integrator.p, Ry, Rp, Rt):
            raise SensitivityError(f"no transition from mode {mode} by guard {gi} to mode {target}")
        D = Ry @ D
        dl = Ry @ dl + Rp @ dpv
    return D, dl
