"""``blademodel simulate MODEL.yaml``: integrate a model from rest and report."""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from ..analysis import mean_square, periodicity_label, vibration_reduction
from ..numeric.mean_square import mean_square_run, without_contacts
from ..numeric import SimulationError, simulate
from ..numeric.limits import check_run_length
from ..progress import Progress
from . import jsonout
from .common import add_model_arguments, add_stepping_arguments, config_and_model
from .output import check_output_file


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``simulate`` subcommand."""
    p = subparsers.add_parser("simulate", help="integrate a model from rest",
                              description="Start at rest, discard M excitation periods, record N, "
                                          "and report periodicity, Poincare samples and counters.")
    add_model_arguments(p)
    p.add_argument("--transient", type=int, default=200, metavar="M", help="periods discarded (default 200)")
    p.add_argument("--periods", type=int, default=100, metavar="N", help="periods recorded (default 100)")
    add_stepping_arguments(p)
    p.add_argument("--record-every", type=int, default=1, metavar="K",
                   help="record the state every K steps (default 1; Poincare samples are always kept)")
    p.add_argument("--kernel", choices=("auto", "product", "contact"), default="auto",
                   help="auto (default): product modes for at most one contact, per-contact modes otherwise")
    p.add_argument("--event-location", choices=("bisection", "predicted"), default=None,
                   help="how events are bracketed (default: bisection on the product kernel, predicted roots "
                        "on the per-contact kernel)")
    p.add_argument("--no-grazing", action="store_true",
                   help="per-contact kernel: do not look for contacts entered and left within one step")
    p.add_argument("--out", metavar="FILE", help="save the full result (.npz)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(run=run)
    return p


def _vibration_reduction(model, result, args) -> tuple[float | None, str | None]:
    """``(P_d, None)`` in percent against the same model without contacts, or ``(None, reason)``.

    ``P_d = (P0 - P) / P0`` is undefined without contacts, when the reference system
    does not move (``P0 = 0``: no force, or a motion below float64's range) or when
    a mean square overflows; the run is kept and the reason reported instead.
    """
    if not model.contacts:
        return None, "the model has no contacts (P_d compares it with itself without contacts)"
    names = model.masses[0].coordinates
    try:
        with np.errstate(over="ignore"):  # an overflow is reported below as an undefined P_d
            P = mean_square(result.y, result.state_names, names)
            P0 = mean_square_run(without_contacts(model), transient=args.transient, periods=args.periods,
                                 steps_per_period=args.steps_per_period, event_tol=args.event_tol, names=names)
    except RuntimeError as e:   # the reference run itself failed
        return None, f"the reference run without contacts failed: {e}"
    if not (math.isfinite(P) and math.isfinite(P0)):
        return None, f"P = {P:g}, P0 = {P0:g}: a mean square of the displacements is not finite"
    try:
        return vibration_reduction(P, P0), None
    except ValueError as e:
        return None, f"{e} (P_d = (P0 - P) / P0 needs P0 > 0)"


def first_harmonics(result, n: int) -> dict | None:
    """First-harmonic amplitude of the first ``n`` states over the recorded periods (None if they are not whole)."""
    from ..analysis import harmonic_amplitudes
    S, r = result.settings["steps_per_period"], result.settings.get("record_every", 1)
    if S % r or len(result.t) < S // r + 1:
        return None
    amp = harmonic_amplitudes(result.y[:, :n], S // r)
    return dict(zip(result.state_names[:n], map(float, amp)))


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
        "harmonic1": first_harmonics(result, len(model.coordinates) * 2),
        "final_state": result.final,
        "final_mode": result.mode_names[result.final_mode],
        "counters": result.counters,
        "params": {**config.model_dump(mode="json", exclude_none=True), **result.params,
                   **result.settings, "period": result.period},
        "status": result.message,
    }
    return out


def _check_up_front(model, args) -> None:
    """Refuse bad settings and a bad ``--out`` before the kernel is built or a step is taken."""
    if args.out:
        check_output_file(args.out, ".npz", what="NumPy .npz archive")
    try:
        check_run_length(model, periods=args.periods, transient=args.transient,
                         steps_per_period=args.steps_per_period, record_every=args.record_every,
                         reference=bool(model.contacts))
    except ValueError as e:  # name the options as the user typed them
        text = str(e)
        for name in ("steps_per_period", "record_every", "transient", "periods"):
            text = text.replace(f"{name} = ", f"--{name.replace('_', '-')} ")
        raise type(e)(text) from None


def _save(path: str, result, report_json: str) -> None:
    extra = {}
    if result.contacts is not None:   # per-contact kernel: each contact's mode and forces per record
        extra = {"contact_names": np.array(result.contacts["names"]), "contact_modes": result.contacts["modes"],
                 "contact_mode_names": np.array([",".join(m) for m in result.contacts["mode_names"]])}
        if "N" in result.contacts:
            extra.update(contact_N=result.contacts["N"], contact_f=result.contacts["f"])
    np.savez_compressed(path, t=result.t, y=result.y, mode=result.mode, poincare=result.poincare,
                        poincare_t=result.poincare_t, state_names=np.array(result.state_names),
                        mode_names=np.array(result.mode_names), report=report_json, **extra)


def run(args: argparse.Namespace) -> int:
    """Run the simulation; return the exit code."""
    config, model = config_and_model(args)
    _check_up_front(model, args)
    try:
        result = simulate(model, periods=args.periods, transient=args.transient,
                          steps_per_period=args.steps_per_period, event_tol=args.event_tol,
                          length_scale=model.length_scale, progress=Progress("periods", label="simulate"), record_every=args.record_every,
                          kernel=args.kernel, method=args.method, event_location=args.event_location,
                          detect_grazing=not args.no_grazing)
    except SimulationError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    rep = report(config, model, result)
    rep["Pd"], why = _vibration_reduction(model, result, args)
    text = jsonout.dumps(rep, {"Pd": why} if why else None)
    if args.out:
        try:
            _save(args.out, result, text)
        except OSError as e:
            print(f"error: --out {args.out!r}: cannot save the result: {e.strerror or e}", file=sys.stderr)
            return 1
    if args.json:
        print(text)
    else:
        print(f"{model.name}: {rep['periodicity']} after {args.transient} periods "
              f"({result.counters['events']} events, {result.counters['steps']} steps)")
        print("final state: " + ", ".join(f"{k}={v:.6g}" for k, v in result.final.items()))
        if rep["harmonic1"]:
            coords = list(rep["harmonic1"])[:len(model.coordinates)]
            print("first-harmonic amplitudes over the recorded periods: "
                  + ", ".join(f"{k}={rep['harmonic1'][k]:.6g}" for k in coords))
        if why and model.contacts:
            print(f"P_d: undefined: {why}")
        if args.out:
            print(f"saved {args.out}")
    return 0
