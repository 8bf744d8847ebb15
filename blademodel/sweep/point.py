"""One point of a sweep: integrate, analyse, return plain arrays (picklable)."""

from __future__ import annotations

import traceback

import numpy as np

from ..analysis import (classify_motion, harmonic_amplitudes, largest_lyapunov, mean_square, poincare_period,
                        vibration_reduction)
from ..config import apply_overrides, config_from_data
from ..numeric.contract import C_EVENTS, N_COUNTERS, N_STATS, S_MAX_CONE_RATIO, STATUS_NAMES
from ..numeric.kernels import make_integrator
from ..numeric.mean_square import mean_square_run, without_contacts

#: Motion codes stored in result files.
MOTION_CODES = {"nonperiodic": 0, "quasi-periodic": -1, "chaos": -2}


def motion_code(label: str) -> int:
    """``"P3"`` -> 3; ``"chaos"`` -> -2; ``"quasi-periodic"`` -> -1; ``"nonperiodic"`` -> 0."""
    return int(label[1:]) if label.startswith("P") else MOTION_CODES[label]


def motion_label(code: int) -> str:
    """Inverse of :func:`motion_code`."""
    return f"P{code}" if code > 0 else {v: k for k, v in MOTION_CODES.items()}[int(code)]


def build_config(base: dict, overrides: dict):
    """The validated config of a point: ``base`` with ``overrides`` applied."""
    return apply_overrides(config_from_data(dict(base), source="study base"), overrides, source="sweep")


_P0_MEMO: dict = {}


def observed(model, names=None) -> tuple[str, ...]:
    """The coordinates a sweep point observes: ``names`` (the study's ``run.observe``), else the first mass's.

    One rule for every model: the Poincare samples and the kept history are of the
    first of them (stored as ``poincare_x1``, ``history_x1`` ..., named in the file's
    ``observed`` attribute: ``x1`` in the paper's pair and in a bladed disk), ``P``
    and ``P_d`` sum the squares of all of them (``x1`` and ``y1`` there, MODEL.md
    section 7).

    Raises
    ------
    ValueError
        If a name is not a coordinate of ``model``.
    """
    if not names:
        return model.masses[0].coordinates
    unknown = [n for n in names if n not in model.coordinates]
    if unknown:
        raise ValueError(f"run.observe = {list(names)}: {', '.join(map(repr, unknown))} is not a coordinate of the "
                         f"model ({', '.join(model.coordinates)})")
    return tuple(names)


def _reference_mean_square(model, run: dict) -> float:
    """``P0``: the same mean for the model without contacts (memoised: a gap or gamma sweep shares it)."""
    model0 = without_contacts(model)
    key = (model0.structure_key(), tuple(sorted(model0.parameters.items())), run["transient"], run["periods"],
           run["steps_per_period"], tuple(observed(model, run.get("observe"))))
    if key not in _P0_MEMO:
        _P0_MEMO[key] = mean_square_run(model0, transient=run["transient"], periods=run["periods"],
                                        steps_per_period=run["steps_per_period"], event_tol=run["event_tol"],
                                        names=observed(model, run.get("observe")))
    return _P0_MEMO[key]


def run_point(base: dict, overrides: dict, run: dict, y0=None) -> dict:
    """Integrate one point from rest (or ``y0``) and analyse it.

    Parameters
    ----------
    base : dict
        Base model config data.
    overrides : dict
        Swept field values of this point (dotted names).
    run : dict
        :class:`~blademodel.sweep.spec.RunSettings` as a dict.
    y0 : ndarray, optional
        Warm start state.

    Returns
    -------
    dict
        ``poincare_x1``, ``poincare_vx1`` (SI, one per recorded period; of the first
        :func:`observed` coordinate, ``x1`` in the paper's models),
        ``length_scale``, ``period``, ``motion`` (code), ``lyapunov`` (1/period),
        ``P``, ``P0``, ``Pd`` (percent), ``events``, ``final_state``, ``harmonic1`` (the
        first-harmonic amplitude of every coordinate and velocity over the recorded
        periods: of the last ``history_periods`` when only those are kept) and, if asked,
        ``history_t``, ``history_x1``, ``history_vx1``; on failure only ``error``.
    """
    try:
        cfg = build_config(base, overrides)
        model = cfg.build()
        integ = make_integrator(model, steps_per_period=run["steps_per_period"], event_tol=run["event_tol"])
        T, S = integ.period, integ.steps_per_period
        transient, periods = run["transient"], run["periods"]
        y = integ.initial_state(y0)
        mode = integ.mode_of(y)
        hist = min(run.get("history_periods", 0), periods)
        want_pd = bool(run.get("vibration_reduction"))
        keep = periods if want_pd else hist  # periods recorded at every step
        # otherwise a lighter record (at least 256 samples a period) gives the first harmonics
        every = 1 if keep else max(d for d in range(1, max(S // 256, 1) + 1) if S % d == 0)
        n_rec = (keep if keep else periods) * (S // every) + 1
        rec = integ.record_buffer(n_rec)
        poinc = np.empty((periods, integ.n_state))
        counters = np.zeros(N_COUNTERS, dtype=np.int64)
        per_contact = integ.kernel == "contact"
        stats = np.zeros(N_STATS)
        extra = {"stats": stats} if per_contact else {}
        status, mode, t = integ.advance(y, mode, 0, transient, counters=counters, **extra)
        if not status:
            status, mode, t = integ.advance(y, mode, transient, transient + periods, poincare=poinc,
                                            counters=counters, **extra,
                                            n_transient=transient, record=rec, record_every=every)
        if status:
            raise RuntimeError(f"integration failed at t = {t:.6g} s ({STATUS_NAMES.get(status, status)})")
        names = integ.state_names
        first = observed(model, run.get("observe"))[0]
        ix, iv = names.index(first), names.index(f"v{first}")
        n_phys = len(model.coordinates) * 2
        scale_len = model.length_scale or float("nan")
        out = {"poincare_x1": poinc[:, ix].copy(), "poincare_vx1": poinc[:, iv].copy(),
               "harmonic1": harmonic_amplitudes(rec[1][:, :n_phys], S // every),
               "length_scale": scale_len, "period": poincare_period(poinc[:, :n_phys]),
               "events": int(counters[C_EVENTS]), "final_state": y.copy(),
               "max_cone_ratio": float(stats[S_MAX_CONE_RATIO]) if per_contact else float("nan")}
        lam = float("nan")
        if run.get("lyapunov_periods", 0):
            ref = abs(scale_len) if np.isfinite(scale_len) and scale_len else max(np.max(np.abs(poinc[:, 0])), 1e-12)
            omega = 2 * np.pi / T
            sc = [ref] * (n_phys // 2) + [ref * omega] * (n_phys // 2) + [ref] * (integ.n_physical - n_phys)
            lam = largest_lyapunov(integ, y, mode, start_period=transient + periods,
                                   periods=run["lyapunov_periods"], scale=sc)
        out["lyapunov"] = lam
        out["motion"] = motion_code(classify_motion(poinc[:, :n_phys], lam if run.get("lyapunov_periods") else None))
        if hist:
            tail = slice(n_rec - (hist * S + 1), n_rec)
            out.update(history_t=rec[0][tail].copy(), history_x1=rec[1][tail, ix].copy(),
                       history_vx1=rec[1][tail, iv].copy())
        if want_pd:
            P, P0 = mean_square(rec[1], names, observed(model, run.get("observe"))), _reference_mean_square(model, run)
            out.update(P=P, P0=P0, Pd=vibration_reduction(P, P0))
        return out
    except Exception as e:  # a failed point is recorded, the sweep goes on
        return {"error": f"{type(e).__name__}: {e}", "traceback": traceback.format_exc(limit=3)}
