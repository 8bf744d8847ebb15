"""``blademodel orbit MODEL.yaml``: a periodic orbit by shooting, its Floquet multipliers and amplitudes."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from ..numeric import SimulationError
from ..numeric.kernels import make_integrator
from ..orbits import FlowError, ShootingError, find_periodic_orbit
from ..sweep.point import observed
from . import jsonout
from .common import (add_jacobian_arguments, add_model_arguments, add_stepping_arguments, check_at_least_one,
                     config_and_model)


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``orbit`` subcommand."""
    p = subparsers.add_parser("orbit", help="find a periodic orbit and its stability (shooting)",
                              description="Integrate M periods from rest for a guess, then solve P(y) = y for "
                                          "the map P over N excitation periods by Newton's method; report the "
                                          "orbit's state at t = 0, its Floquet multipliers and amplitudes. "
                                          "Unstable orbits are found too.")
    add_model_arguments(p)
    p.add_argument("--periods", type=int, default=1, metavar="N", help="period of the orbit in excitation "
                                                                       "periods (default 1)")
    p.add_argument("--transient", type=int, default=20, metavar="M",
                   help="periods from rest before the first Newton step (default 20)")
    p.add_argument("--tol", type=float, default=1e-10, help="scaled residual to reach (default 1e-10)")
    p.add_argument("--max-iter", type=int, default=30, metavar="K", help="Newton steps allowed (default 30)")
    add_stepping_arguments(p)
    add_jacobian_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(run=run)
    return p


def _check(args) -> None:
    check_at_least_one(args, ("periods", "max_iter", "steps_per_period"))
    if args.transient < 0:
        raise ValueError(f"--transient must be >= 0, got {args.transient}")
    if not args.tol > 0:
        raise ValueError(f"--tol must be > 0, got {args.tol}")


def report(orbit, mode_name: str) -> dict:
    """The JSON report of an orbit (SI units)."""
    mu = orbit.multipliers
    return {
        "periods": orbit.periods,
        "least_period": orbit.least_period(),
        "state": dict(zip(orbit.state_names, map(float, orbit.state))),
        "mode": mode_name,
        "multipliers": [{"re": float(m.real), "im": float(m.imag), "abs": float(abs(m))} for m in mu],
        "stable": orbit.stable,
        "amplitudes": orbit.amplitudes(),
        "first_harmonic": {n: float(abs(orbit.harmonic(n))) for n in orbit.state_names},
        "residual": orbit.residual,
        "history": orbit.history,
    }


def run(args: argparse.Namespace) -> int:
    """Find the orbit; return the exit code."""
    _check(args)
    _, model = config_and_model(args)
    ig = make_integrator(model, steps_per_period=args.steps_per_period, event_tol=args.event_tol,
                         method=args.method)
    try:
        orbit = find_periodic_orbit(model, periods=args.periods, transient=args.transient, tol=args.tol,
                                    max_iter=args.max_iter, integrator=ig, jacobian=args.jacobian,
                                    workers=args.workers)
    except (ShootingError, FlowError, SimulationError) as e:
        print(f"error: {e}", file=sys.stderr)
        if getattr(e, "least_tol", None) is not None:
            print(f"hint: --tol {e.least_tol:g}", file=sys.stderr)
        return 1
    mode = orbit.mode
    mode_name = ig.mode_label(mode) if isinstance(mode, np.ndarray) else ig.mode_names[int(mode)]
    rep = report(orbit, mode_name)
    rep["P_d"], why = _reduction(orbit, model)
    if args.json:
        print(jsonout.dumps(rep))
        return 0
    big = orbit.multipliers[0]
    least = rep["least_period"]
    run_again = "" if least == orbit.periods else \
        f" (of least period {least}: the period-{least} orbit run {orbit.periods // least} times)"
    print(f"{model.name}: period-{orbit.periods} orbit{run_again}, {'stable' if orbit.stable else 'UNSTABLE'} "
          f"(largest multiplier {big.real:.6g}{big.imag:+.6g}i, |mu| = {abs(big):.6g}); "
          f"{len(orbit.history) - 1} Newton steps, scaled residual {orbit.residual:.2g}")
    print(f"state at t = 0 ({mode_name}): " + ", ".join(f"{k}={v:.6g}" for k, v in rep["state"].items()))
    print("amplitudes: " + ", ".join(f"{k}={v:.6g}" for k, v in rep["amplitudes"].items()))
    print(f"vibration reduction P_d of {', '.join(observed(model))}: {rep['P_d']:.4g} %" if rep["P_d"] is not None else
          f"vibration reduction P_d: none ({why})")
    return 0


def _reduction(orbit, model) -> tuple:
    """``(P_d in percent, None)`` of the orbit against the model without contacts in closed form, or
    ``(None, why)`` (:func:`~blademodel.analysis.contact_free.contact_free_mean_squares`)."""
    from ..analysis.contact_free import contact_free_mean_squares
    from ..analysis.reduction import mean_square, vibration_reduction
    names = list(observed(model))
    try:
        ms0 = contact_free_mean_squares(model)
    except ValueError as e:
        return None, str(e)
    P = mean_square(orbit.y, orbit.state_names, names)
    return vibration_reduction(P, sum(ms0[n] for n in names)), None
