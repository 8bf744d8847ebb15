"""Incremental NetCDF storage of a sweep, one point at a time, with resume.

The file is laid out in full when the sweep starts, in the NetCDF classic
(64-bit offset) format: every output filled with NaN, ``done = 0``. After that
the header never changes; a finished point's values are written in place and
synced to disk *before* its ``done`` flag is set, by the single writer process.
So a sweep killed at any instant leaves a readable file in which every point
marked done is complete; the others are run again on resume.
The study, the base config and the run settings travel in the file's
attributes, so a result file says how it was made.
"""

from __future__ import annotations

import json
from pathlib import Path

import netCDF4
import numpy as np

from .. import __version__

#: Per-point scalars. ``max_cone_ratio``: the largest ``|f| / (mu N)`` of a sticking
#: Coulomb contact (per-contact kernel; NaN for the product kernel).
SCALARS = ("length_scale", "period", "motion", "lyapunov", "P", "P0", "Pd", "events", "max_cone_ratio")
INTS = ("period", "motion", "events")
LAW_CHARS, ERROR_CHARS = 32, 400
FORMAT = "NETCDF3_64BIT_OFFSET"


def _chars(text: str, n: int) -> np.ndarray:
    return netCDF4.stringtoarr(text.encode("utf-8", "replace")[:n].decode("utf-8", "ignore"), n)


def study_signature(study_json: str) -> str:
    """What must match for a file to be resumed: the study without presentation fields."""
    d = json.loads(study_json)
    for k in ("title", "paper", "plot"):
        d.pop(k, None)
    if not d.get("law_options"):
        d.pop("law_options", None)   # files written before law_options existed still resume
    return json.dumps(d, sort_keys=True)


def create(path: Path, *, study_json: str, fields: list[str], values: list[list], laws: list[str],
           periods: int, n_state: int, history: int) -> None:
    """Lay out a new result file for ``len(values)`` points."""
    path = Path(path)
    tmp = path.with_suffix(".tmp.nc")
    with netCDF4.Dataset(tmp, "w", format=FORMAT) as ds:
        n = len(values)
        ds.createDimension("point", n)
        ds.createDimension("law_chars", LAW_CHARS)
        ds.createDimension("error_chars", ERROR_CHARS)
        ds.createDimension("sample", periods)
        ds.createDimension("state", n_state)
        if history:
            ds.createDimension("time", history)
        ds.setncattr("study", study_json)
        ds.setncattr("signature", study_signature(study_json))
        ds.setncattr("fields", json.dumps(fields))
        ds.setncattr("blademodel_version", __version__)
        for j, f in enumerate(fields):
            v = ds.createVariable(f"param_{f}", "f8", ("point",))
            v[:] = [row[j] for row in values]
        lv = ds.createVariable("law", "S1", ("point", "law_chars"))
        lv.set_auto_chartostring(False)
        for i, law in enumerate(laws):
            lv[i, :] = _chars(law, LAW_CHARS)
        ds.createVariable("done", "i1", ("point",))[:] = 0
        for name in SCALARS:
            kind = "i4" if name in INTS else "f8"
            var = ds.createVariable(name, kind, ("point",), fill_value=-999 if kind == "i4" else np.nan)
            var[:] = -999 if kind == "i4" else np.nan
        for name in ("poincare_x1", "poincare_vx1"):
            ds.createVariable(name, "f8", ("point", "sample"), fill_value=np.nan)
        ds.createVariable("final_state", "f8", ("point", "state"), fill_value=np.nan)
        if history:
            for name in ("history_t", "history_x1", "history_vx1"):
                ds.createVariable(name, "f8", ("point", "time"), fill_value=np.nan)
        ev = ds.createVariable("error", "S1", ("point", "error_chars"))
        ev.set_auto_chartostring(False)
        ev[:] = np.zeros((n, ERROR_CHARS), dtype="S1")
    tmp.replace(path)


def pending(path: Path, study_json: str) -> list[int]:
    """Indices of the points of ``path`` not yet done; checks the file is this study's."""
    with netCDF4.Dataset(path, "r") as ds:
        if ds.getncattr("signature") != study_signature(study_json):
            raise ValueError(f"{path} holds a different study or settings; remove it or pass --restart")
        done = np.asarray(ds["done"][:])
    return [int(i) for i in np.flatnonzero(done == 0)]


def write_point(path: Path, index: int, out: dict) -> None:
    """Write one finished (or failed) point and mark it done."""
    with netCDF4.Dataset(path, "a") as ds:
        ds["error"].set_auto_chartostring(False)
        if "error" in out:
            ds["error"][index, :] = _chars(out["error"] or "failed", ERROR_CHARS)
        else:
            for name in SCALARS:
                if name in out and name in ds.variables:   # files written before a variable existed resume
                    ds[name][index] = out[name]
            for name in ("poincare_x1", "poincare_vx1", "final_state", "history_t", "history_x1", "history_vx1"):
                if name in out and name in ds.variables:
                    ds[name][index, : len(out[name])] = out[name]
        ds.sync()  # the values reach the disk before the point is marked done
        ds["done"][index] = 1


def final_state(path: Path, index: int) -> np.ndarray | None:
    """Final state of a finished point (for a warm start), or ``None``.

    States of laws with fewer internal states are padded with NaN in the file.
    """
    with netCDF4.Dataset(path, "r") as ds:
        if not ds["done"][index]:
            return None
        v = np.asarray(ds["final_state"][index, :].filled(np.nan), dtype=float)
    v = v[~np.isnan(v)]
    return v if v.size else None
