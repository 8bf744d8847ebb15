"""Incremental NetCDF storage of a sweep, one point at a time, with resume.

The file is laid out in full when the sweep starts (every output filled with
NaN, ``done = 0``); each finished point is written and flushed at once by the
single writer process, so a killed sweep loses at most the points in flight.
The study, the base config and the run settings travel in the file's
attributes, so a result file says how it was made.
"""

from __future__ import annotations

import json
from pathlib import Path

import netCDF4
import numpy as np

from .. import __version__

SCALARS = ("length_scale", "period", "motion", "lyapunov", "P", "P0", "Pd", "events")
INTS = ("period", "motion", "events")


def study_signature(study_json: str) -> str:
    """What must match for a file to be resumed: the study without presentation fields."""
    d = json.loads(study_json)
    for k in ("title", "paper", "plot"):
        d.pop(k, None)
    return json.dumps(d, sort_keys=True)


def create(path: Path, *, study_json: str, fields: list[str], values: list[list], laws: list[str],
           periods: int, n_state: int, history: int) -> None:
    """Lay out a new result file for ``len(values)`` points."""
    path = Path(path)
    tmp = path.with_suffix(".tmp.nc")
    with netCDF4.Dataset(tmp, "w", format="NETCDF4") as ds:
        n = len(values)
        ds.createDimension("point", n)
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
        lv = ds.createVariable("law", str, ("point",))
        for i, law in enumerate(laws):
            lv[i] = law
        ds.createVariable("done", "i1", ("point",))[:] = 0
        for name in SCALARS:
            kind = "i8" if name in INTS else "f8"
            var = ds.createVariable(name, kind, ("point",), fill_value=-999 if kind == "i8" else np.nan)
            var[:] = -999 if kind == "i8" else np.nan
        for name in ("poincare_x1", "poincare_vx1"):
            ds.createVariable(name, "f8", ("point", "sample"), fill_value=np.nan)
        ds.createVariable("final_state", "f8", ("point", "state"), fill_value=np.nan)
        if history:
            for name in ("history_t", "history_x1", "history_vx1"):
                ds.createVariable(name, "f8", ("point", "time"), fill_value=np.nan)
        ds.createVariable("error", str, ("point",))
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
        if "error" in out:
            ds["error"][index] = out["error"]
        else:
            for name in SCALARS:
                if name in out:
                    ds[name][index] = out[name]
            for name in ("poincare_x1", "poincare_vx1", "final_state", "history_t", "history_x1", "history_vx1"):
                if name in out and name in ds.variables:
                    ds[name][index, : len(out[name])] = out[name]
            ds["error"][index] = ""
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
