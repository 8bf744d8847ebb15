"""``blademodel simulate MODEL.yaml``: integrate a model from rest and report."""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from ..analysis import mean_square, periodicity_label, vibration_reduction
from ..numeric.mean_square import mean_square_run, without_contacts
from ..config import apply_overrides, load_config
from ..numeric import SimulationError, simulate
from .common import add_model_arguments, parse_overrides


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``simulate`` subcommand."""
    p = subparsers.add_parser("simulate", help="integrate a model from rest",
                              description="Start at rest, discard M excitation periods, record N, "
                                          "and report periodicity, Poincare samples and counters.")
    add_model_arguments(p)
    p.add_argument("--transient", type=int, default=200, metavar="M", help="periods discarded (default 200)")
    p.add_argument("--periods", type=int, default=100, metavar="N", help="periods recorded (default 100)")
    p.add_argument("--steps-per-period", type=int, default=1000, metavar="S",
                   help="RK4 steps per excitation period (default 1000)")
    p.add_argument("--event-tol", type=float, default=1e-10, metavar="E",
                   help="event bracket, as a fraction of the step (default 1e-10)")
    p.add_argument("--record-every", type=int, default=1, metavar="K",
                   help="record the state every K steps (default 1; Poincare samples are always kept)")
    p.add_argument("--kernel", choices=("auto", "product", "contact"), default="auto",
                   help="auto (default): product modes for at most one contact, per-contact modes otherwise")
    p.add_argument("--out", metavar="FILE", help="save the full result (.npz)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(run=run)
    return p


def _progress(done: int, total: int) -> None:
    if sys.stderr.isatty():
        bar = "#" * int(30 * done / total)
        print(f"\r[{bar:<30}] {done}/{total} periods", end="" if done < total else "\n", file=sys.stderr)


def _vibration_reduction(model, result, args) -> float | None:
    """``P_d`` in percent against the same model without contacts (None without contacts)."""
    if not model.contacts:
        return None
    names = model.masses[0].coordinates
    P = mean_square(result.y, result.state_names, names)
    P0 = mean_square_run(without_contacts(model), transient=args.transient, periods=args.periods,
                         steps_per_period=args.steps_per_period, event_tol=args.event_tol, names=names)
    return vibration_reduction(P, P0)


def report(config, model, result) -> dict:
    """The JSON report of a run (SI units; ``X1 = x1 / gap``)."""
    scale = result.length_scale
    coord = result.state_names[0]
    x = result.poincare[:, result.index(coord)]
    key = coord.upper() if coord[-1].isdigit() else coord
    out = {
        "periodicity": periodicity_label(result.poincare[:, : len(model.coordinates) * 2])
        if len(result.poincare) > 1 else "unknown",
        "poincare": {key if scale else coord: list(map(float, x / scale if scale else x))},
        "final_state": result.final,
        "final_mode": result.mode_names[result.final_mode],
        "counters": result.counters,
        "params": {**config.model_dump(mode="json", exclude_none=True), **result.params,
                   **result.settings, "period": result.period},
        "status": result.message,
    }
    return out


def run(args: argparse.Namespace) -> int:
    """Run the simulation; return the exit code."""
    config = apply_overrides(load_config(args.model), parse_overrides(args.overrides))
    model = config.build()
    try:
        result = simulate(model, periods=args.periods, transient=args.transient,
                          steps_per_period=args.steps_per_period, event_tol=args.event_tol,
                          length_scale=model.length_scale, progress=_progress, record_every=args.record_every,
                          kernel=args.kernel)
    except SimulationError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    rep = report(config, model, result)
    rep["Pd"] = _vibration_reduction(model, result, args)
    if args.out:
        extra = {}
        if result.contacts is not None:   # per-contact kernel: each contact's mode and forces per record
            extra = {"contact_names": np.array(result.contacts["names"]), "contact_modes": result.contacts["modes"],
                     "contact_mode_names": np.array([",".join(m) for m in result.contacts["mode_names"]])}
            if "N" in result.contacts:
                extra.update(contact_N=result.contacts["N"], contact_f=result.contacts["f"])
        np.savez_compressed(args.out, t=result.t, y=result.y, mode=result.mode, poincare=result.poincare,
                            poincare_t=result.poincare_t, state_names=np.array(result.state_names),
                            mode_names=np.array(result.mode_names), report=json.dumps(rep), **extra)
    if args.json:
        print(json.dumps(rep))
    else:
        print(f"{model.name}: {rep['periodicity']} after {args.transient} periods "
              f"({result.counters['events']} events, {result.counters['steps']} steps)")
        print("final state: " + ", ".join(f"{k}={v:.6g}" for k, v in result.final.items()))
        if args.out:
            print(f"saved {args.out}")
    return 0
