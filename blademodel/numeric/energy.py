"""Mechanical energy and the energy balance of a simulation (not on the hot path)."""

from __future__ import annotations

import numpy as np
import sympy as sp

from ..model import Model
from .compiled import derive_cached
from .result import SimulationResult


def energy_function(model: Model):
    """``E(mode, y, p_raw)``: kinetic + springs + closed contacts + friction-law springs.

    Parameters
    ----------
    model : Model

    Returns
    -------
    callable
        Takes a mode index, a state vector (physical states first) and the raw
        parameter vector in ``model.parameters`` order.
    """
    system = derive_cached(model)
    args = [system.state, system.params]
    base = system.energy["kinetic"] + system.energy["potential"]
    funcs = [sp.lambdify(args, base + c + law, modules="math")
             for c, law in zip(system.energy["contact"], system.energy["law"])]
    n = len(system.state)

    def E(mode: int, y, p) -> float:
        return funcs[mode](list(y[:n]), list(p))
    return E


def energy_balance(model: Model, result: SimulationResult) -> dict:
    """Energy change against input work minus dissipation over the recorded window.

    ``result`` must come from ``simulate(model, ..., energy=True)``; the balance
    runs from its first record to its final state.

    Returns
    -------
    dict
        ``dE`` (energy change), ``W_in``, ``D_visc``, ``D_fric`` (over the window),
        ``residual`` = ``dE - (W_in - D_visc - D_fric)`` and ``throughput`` (the sum
        of the magnitudes of the terms, the scale the residual is judged against).
    """
    if "W_in" not in result.state_names:
        raise ValueError("the result has no energy accumulators: simulate with energy=True")
    y0, y1 = result.y[0], result.final_state
    if result.settings.get("kernel") == "contact":
        from .contact_kernel import ContactIntegrator
        integ = ContactIntegrator(model, steps_per_period=result.steps_per_period, period=result.period,
                                  check_stability=False, energy=True)
        dE = (integ.mechanical_energy(y1, result.final_contact_modes)
              - integ.mechanical_energy(y0, result.contacts["modes"][0]))
    else:
        E = energy_function(model)
        p = np.array([model.parameters[n] for n in result.params], dtype=float)
        dE = E(result.final_mode, y1, p) - E(int(result.mode[0]), y0, p)
    W, Dv, Df = (y1[result.index(k)] - y0[result.index(k)] for k in ("W_in", "D_visc", "D_fric"))
    residual = dE - (W - Dv - Df)
    return {"dE": dE, "W_in": W, "D_visc": Dv, "D_fric": Df, "residual": residual,
            "throughput": abs(W) + abs(Dv) + abs(Df) + abs(dE)}
