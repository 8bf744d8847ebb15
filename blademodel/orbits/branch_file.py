"""A continued branch in a NetCDF file (one point per record), and back."""

from __future__ import annotations

import json
from pathlib import Path

import netCDF4
import numpy as np

from .. import __version__
from ..sweep.cf import CONVENTIONS, field_metadata
from .branch import Branch, SpecialPoint

#: Global attribute ``blademodel_kind`` of a branch file.
KIND = "branch"


def save_branch(branch: Branch, path, config=None, run: dict | None = None) -> None:
    """Write ``branch`` to the NetCDF file ``path`` (written whole, then moved into place).

    Variables: the field's value per ``point`` (a coordinate), the section state,
    amplitudes and first harmonics (magnitude and phase) per ``point`` and ``state``, the
    Poincare samples per ``point``, ``section`` (``t = k T``) and ``state``
    (DOF names as a string coordinate), the multipliers (real and imaginary parts)
    per ``point`` and ``multiplier``, ``stable``, and the special points (kind,
    value, multiplier) along ``special``; what it cost (``integrations``, ``replays``) in
    global attributes. The file follows CF-1.8: every dimension has
    its coordinate variable, every variable a ``long_name`` (the field its ``units``,
    from the config's description), the field is an auxiliary coordinate of every
    per-point variable; the config (if given) is stored as JSON in the global
    attribute ``config``, and ``run`` (the settings that made the branch, so that a
    re-run can tell its own unfinished file) in ``run``. Each orbit's hybrid mode at
    the section (``section_mode``, per ``point`` and ``mode_entry``) and the global
    attribute ``complete`` (0 for a checkpoint or an interrupted run) let a
    continuation resume from the file.
    """
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    k, n = branch.states.shape
    with netCDF4.Dataset(tmp, "w") as ds:
        ds.Conventions = CONVENTIONS
        ds.title = f"periodic orbits continued in {branch.field}"
        ds.source = f"blademodel {__version__}"
        ds.history = f"created by blademodel {__version__} (blademodel continue)"
        ds.blademodel_kind = KIND
        ds.blademodel_version = __version__
        ds.field = branch.field
        ds.periods = branch.periods
        ds.message = branch.message
        ds.integrations = branch.integrations
        ds.replays = branch.replays
        ds.complete = int(branch.complete)
        if config is not None:
            ds.config = json.dumps(config.model_dump(mode="json"))
        if run is not None:
            ds.run = json.dumps(run, sort_keys=True)
        ds.createDimension("point", k)
        ds.createDimension("state", n)
        ds.createDimension("multiplier", n)
        ds.createDimension("special", len(branch.special))
        ds.createDimension("section", branch.periods)
        modes = branch.modes.shape[0] == k and branch.modes.shape[1] > 0   # unknown in files written before
        if modes:
            ds.createDimension("mode_entry", branch.modes.shape[1])
        for dim, long in (("point", "index of the orbit along the branch"),
                          ("section", "index k of the Poincare sample at t = k T"),
                          *([("mode_entry", "entry of the hybrid mode (one per contact on the per-contact kernel)")]
                            if modes else []),
                          ("multiplier", "index of the Floquet multiplier, largest modulus first"),
                          ("special", "index of the special point")):
            v = ds.createVariable(dim, "i8", (dim,))
            v[:] = np.arange(len(ds.dimensions[dim]))
            v.long_name = long
        v = ds.createVariable("state", str, ("state",))
        for i, s in enumerate(branch.state_names):
            v[i] = s
        v.long_name = "name of the state: coordinates, their velocities (v...), then friction-law states"
        v = ds.createVariable(branch.field, "f8", ("point",))
        v[:] = branch.params
        long_name, units = field_metadata(config, branch.field) if config is not None else (None, None)
        v.long_name = long_name or f"continued field {branch.field}"
        if units:
            v.units = units
        for name, data, long in (("section_state", branch.states, "state at t = 0 (SI units)"),
                                 ("amplitude", branch.amplitudes, "half the peak-to-peak excursion over the orbit"),
                                 ("harmonic1_abs", np.abs(branch.harmonics), "first-harmonic amplitude"),
                                 ("harmonic1_phase", np.angle(branch.harmonics), "first-harmonic phase, rad"),
                                 *([("mean_square", branch.mean_squares, "time-mean square over the orbit "
                                     "(SI units squared; the P of P_d)")]
                                   if branch.mean_squares.shape == branch.states.shape else [])):
            v = ds.createVariable(name, "f8", ("point", "state"))
            v[:] = data
            v.long_name = long
        v = ds.createVariable("section_samples", "f8", ("point", "section", "state"))
        v[:] = branch.sections
        v.long_name = "states at t = k T, k = 0 .. periods - 1 (Poincare samples of the orbit)"
        for name, data in (("multiplier_re", branch.multipliers.real), ("multiplier_im", branch.multipliers.imag)):
            v = ds.createVariable(name, "f8", ("point", "multiplier"))
            v[:] = data
            v.long_name = "Floquet multipliers, largest modulus first"
        if modes:
            v = ds.createVariable("section_mode", "i8", ("point", "mode_entry"))
            v[:] = branch.modes
            v.long_name = "hybrid mode of the orbit at t = 0 (the kernel's mode number, or each contact's)"
        v = ds.createVariable("events", "i8", ("point",))
        v[:] = branch.events
        v.long_name = "events per orbit"
        v = ds.createVariable("residual", "f8", ("point",))
        v[:] = branch.residuals
        v.long_name = "scaled residual max |P(y) - y| / scale of the orbit"
        v = ds.createVariable("stable", "i1", ("point",))
        v[:] = branch.stable.astype(np.int8)
        v.long_name = "1: every multiplier inside the unit circle"
        v = ds.createVariable("special_kind", str, ("special",))
        for i, p in enumerate(branch.special):
            v[i] = p.kind
        for name, data in (("special_" + branch.field, [p.param for p in branch.special]),
                           ("special_multiplier_re", [p.multiplier.real for p in branch.special]),
                           ("special_multiplier_im", [p.multiplier.imag for p in branch.special]),
                           ("special_index", [p.index for p in branch.special]),
                           ("special_bracket_lo", [np.nan if p.bracket is None else p.bracket[0]
                                                   for p in branch.special]),
                           ("special_bracket_hi", [np.nan if p.bracket is None else p.bracket[1]
                                                   for p in branch.special])):
            v = ds.createVariable(name, "f8" if "index" not in name else "i8", ("special",))
            v[:] = np.asarray(data)
        ds["special_kind"].long_name = ("kind of special point: fold, branch-point, period-doubling, neimark-sacker, "
                                        "grazing, nonsmooth-fold, border-collision, gap")
        ds["special_" + branch.field].long_name = f"{branch.field} at the special point"
        ds["special_multiplier_re"].long_name = "real part of the critical multiplier"
        ds["special_multiplier_im"].long_name = "imaginary part of the critical multiplier"
        ds["special_index"].long_name = "point of the branch after which the special point lies"
        for end in ("lo", "hi"):
            ds["special_bracket_" + end].long_name = (f"{branch.field} at the {'lower' if end == 'lo' else 'upper'} "
                                                      "end of the interval known to hold the special point, where "
                                                      "its location ended wider than locate_tol (NaN: located)")
        ds["multiplier_im"].long_name = "Floquet multipliers, largest modulus first (imaginary parts)"
        ds["multiplier_re"].long_name = "Floquet multipliers, largest modulus first (real parts)"
        for name, var in ds.variables.items():
            if var.dimensions[:1] == ("point",) and name != "point":
                var.coordinates = branch.field
    tmp.replace(path)


def is_branch_file(path) -> bool:
    """Whether ``path`` is a NetCDF file written by :func:`save_branch`."""
    try:
        with netCDF4.Dataset(path) as ds:
            return getattr(ds, "blademodel_kind", None) == KIND or (
                "section_state" in ds.variables and "field" in ds.ncattrs())
    except (OSError, RuntimeError):
        return False


def load_branch(path) -> Branch:
    """The branch of a file written by :func:`save_branch` (special points without their states)."""
    with netCDF4.Dataset(path) as ds:
        name = ds.field
        mu = ds["multiplier_re"][:].data + 1j * ds["multiplier_im"][:].data
        special = [SpecialPoint(kind=str(ds["special_kind"][i]), param=float(ds["special_" + name][i]),
                                state=np.empty(0),
                                multiplier=complex(ds["special_multiplier_re"][i], ds["special_multiplier_im"][i]),
                                index=int(ds["special_index"][i]), bracket=_bracket(ds, i))
                   for i in range(len(ds.dimensions["special"]))]
        return Branch(field=name, periods=int(ds.periods), params=ds[name][:].data.copy(),
                      states=ds["section_state"][:].data.copy(), multipliers=mu,
                      stable=ds["stable"][:].data.astype(bool), amplitudes=ds["amplitude"][:].data.copy(),
                      events=ds["events"][:].data.copy(),
                      residuals=ds["residual"][:].data.copy() if "residual" in ds.variables else np.zeros(0),
                      sections=ds["section_samples"][:].data.copy() if "section_samples" in ds.variables
                      else ds["section_state"][:].data[:, None, :].copy(),
                      harmonics=ds["harmonic1_abs"][:].data * np.exp(1j * ds["harmonic1_phase"][:].data),
                      special=special, state_names=[str(s) for s in ds["state"][:]], message=ds.message,
                      integrations=int(getattr(ds, "integrations", 0)), replays=int(getattr(ds, "replays", 0)),
                      modes=ds["section_mode"][:].data.astype(np.int64) if "section_mode" in ds.variables
                      else np.zeros((0, 1), dtype=np.int64),
                      complete=bool(getattr(ds, "complete", 1)),
                      mean_squares=ds["mean_square"][:].data.copy() if "mean_square" in ds.variables
                      else np.full(ds["section_state"].shape, np.nan))


def _bracket(ds, i: int) -> tuple | None:
    """The ``i``-th special point's bracket in a branch file (None where located, or in a file without brackets)."""
    if "special_bracket_lo" not in ds.variables:
        return None
    lo, hi = float(ds["special_bracket_lo"][i]), float(ds["special_bracket_hi"][i])
    return None if np.isnan(lo) else (lo, hi)


def branch_origin(path) -> tuple[dict | None, dict | None]:
    """The ``run`` settings and the config stored in a branch file (None for what it lacks, or if it is none)."""
    if not Path(path).is_file() or not is_branch_file(path):
        return None, None
    with netCDF4.Dataset(path) as ds:
        attrs = ds.ncattrs()
        return (json.loads(ds.run) if "run" in attrs else None, json.loads(ds.config) if "config" in attrs else None)
