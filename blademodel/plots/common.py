"""Shared helpers of the figure modules: labels, scales, motion classes, point selection.

Everything here reads a result :class:`xarray.Dataset` as returned by
:func:`blademodel.sweep.open_result` (``attrs["study"]`` a dict,
``attrs["fields"]`` a list); a dataset whose attributes are still the JSON
strings of the file is accepted too.
"""

from __future__ import annotations

import json
import math

import numpy as np

from ..sweep.point import motion_label

#: Plot-only motion codes (never stored in a result file).
FAILED = -3
NOT_RUN = -4

#: Excitation frequency (rad/s) when a result file says nothing about it.
DEFAULT_OMEGA = 290.0

#: Display name, unit and factor from SI of the fields the paper sweeps.
_FIELDS = {
    "gamma": ("\u03b3", "", 1.0),
    "gap": ("\u0394", "\u00b5m", 1e6),
    "Delta": ("\u0394", "\u00b5m", 1e6),
    "F0": ("$F_0$", "N", 1.0),
    "omega": ("\u03c9", "rad/s", 1.0),
    "mu": ("\u03bc", "", 1.0),
    "kd": ("$k_d$", "N/m", 1.0),
    "alpha": ("\u03b1", "rad", 1.0),
    "beta": ("\u03b2", "rad", 1.0),
}

#: Display names of the friction laws.
LAW_NAMES = {"coulomb": "Coulomb", "bilinear": "bilinear", "none": "no friction"}


def study_of(ds) -> dict:
    """The study settings of a result dataset, as a dict."""
    st = ds.attrs.get("study", {})
    return json.loads(st) if isinstance(st, str) else dict(st)


def fields_of(ds) -> list[str]:
    """The swept (or case) field names of a result dataset."""
    f = ds.attrs.get("fields")
    if f is None:
        return [v[len("param_"):] for v in ds.variables if v.startswith("param_")]
    return json.loads(f) if isinstance(f, str) else list(f)


def field_axis(field: str) -> tuple[str, float]:
    """Axis label and factor from SI for a swept field.

    Parameters
    ----------
    field : str
        Config field name (nested names with dots: the last part names it).

    Returns
    -------
    label : str
        E.g. ``"Δ (µm)"`` or ``"γ"``.
    factor : float
        Multiply the stored SI values by this to get the plotted values.
    """
    name, unit, factor = _FIELDS.get(field.split(".")[-1], (field, "", 1.0))
    if name == field.split(".")[-1] and "." in field:
        name = field
    return (f"{name} ({unit})" if unit else name), factor


def field_values(ds, field: str) -> np.ndarray:
    """Plotted values of ``field`` per point (SI times the :func:`field_axis` factor)."""
    return np.asarray(ds[f"param_{field}"].values, dtype=float) * field_axis(field)[1]


def format_field(field: str, value: float) -> str:
    """``"γ = 5.3"``, ``"Δ = 40 µm"``: a point's field value for a title."""
    name, unit, factor = _FIELDS.get(field.split(".")[-1], (field, "", 1.0))
    v = value * factor
    return f"{name} = {v:.4g}" + (f" {unit}" if unit else "")


def laws_of(ds) -> list[str]:
    """The friction laws of a result dataset, in the order of its points."""
    seen: list[str] = []
    for law in np.asarray(ds["law"].values).astype(str):
        if law not in seen:
            seen.append(law)
    return seen


def law_name(law: str) -> str:
    """Display name of a friction law."""
    return LAW_NAMES.get(law, law)


def errors(ds) -> np.ndarray:
    """Error message per point (``""`` when the point ran, or did not run yet)."""
    if "error" not in ds:
        return np.full(ds.sizes["point"], "", dtype=object)
    out = []
    for e in np.asarray(ds["error"].values, dtype=object):
        out.append("" if e is None or (isinstance(e, float) and math.isnan(e)) else str(e))
    return np.asarray(out, dtype=object)


def motion_codes(ds) -> np.ndarray:
    """Motion code per point, with :data:`FAILED` and :data:`NOT_RUN` for the rest.

    Returns
    -------
    ndarray of int
        ``n > 0`` period-n, ``0`` nonperiodic, ``-1`` quasi-periodic, ``-2``
        chaos, ``-3`` failed, ``-4`` not run yet.
    """
    n = ds.sizes["point"]
    motion = np.asarray(ds["motion"].values, dtype=float) if "motion" in ds else np.full(n, np.nan)
    done = np.asarray(ds["done"].values, dtype=float) if "done" in ds else np.ones(n)
    err = errors(ds)
    codes = np.where(np.isfinite(motion) & (motion > -900), motion, NOT_RUN).astype(int)
    codes[(done == 0) | ~np.isfinite(done)] = NOT_RUN
    codes[(err != "") & (done != 0)] = FAILED
    return codes


def code_label(code: int) -> str:
    """Label of a (plot) motion code: ``"P3"``, ``"chaos"``, ``"failed"``, ``"not run"``."""
    code = int(code)
    if code == FAILED:
        return "failed"
    if code == NOT_RUN:
        return "not run"
    return motion_label(code)


def steps_per_period(ds) -> int:
    """RK4 steps per excitation period of the study (1000 when not recorded)."""
    return int(study_of(ds).get("run", {}).get("steps_per_period", 1000))


def _find_key(data, key):
    if isinstance(data, dict):
        if key in data and isinstance(data[key], (int, float)):
            return float(data[key])
        for v in data.values():
            found = _find_key(v, key)
            if found is not None:
                return found
    elif isinstance(data, list):
        for v in data:
            found = _find_key(v, key)
            if found is not None:
                return found
    return None


def excitation_omega(ds, point: int) -> float:
    """Excitation frequency (rad/s) of one point.

    From the point's time history (sample spacing times steps per period),
    else a swept ``omega``, else the study's base config, else 290 rad/s.
    """
    if "history_t" in ds:
        t = np.asarray(ds["history_t"].values[point], dtype=float)
        t = t[np.isfinite(t)]
        if len(t) > 1 and t[-1] > t[0]:
            T = (t[-1] - t[0]) / (len(t) - 1) * steps_per_period(ds)
            return 2 * math.pi / T
    for f in fields_of(ds):
        if f.split(".")[-1] == "omega":
            v = float(ds[f"param_{f}"].values[point])
            if np.isfinite(v) and v > 0:
                return v
    found = _find_key(study_of(ds).get("base", {}), "omega")
    return found if found and found > 0 else DEFAULT_OMEGA


def length_scales(ds) -> np.ndarray:
    """Gap per point (m), NaN where the file has none."""
    if "length_scale" not in ds:
        return np.full(ds.sizes["point"], np.nan)
    return np.asarray(ds["length_scale"].values, dtype=float)


def use_gap_scale(ds, points=None) -> bool:
    """Whether ``X1 = x1 / gap`` can be shown for these points (every gap finite and > 0)."""
    ls = length_scales(ds)
    ran = motion_codes(ds) > FAILED
    sel = ran if points is None else np.isin(np.arange(len(ls)), points) & ran
    ls = ls[sel]
    return bool(len(ls)) and bool(np.all(np.isfinite(ls) & (ls > 0)))


def displacement(ds, points, physical: bool | None = None) -> tuple[np.ndarray, str, str]:
    """Divisor per point and axis labels for ``x1`` and ``x1'``.

    Parameters
    ----------
    ds : xarray.Dataset
    points : array_like of int
        Points that will be shown.
    physical : bool, optional
        ``True``: ``x1`` in µm; ``False``: ``X1 = x1 / gap``; default: ``X1``
        unless some shown point has no positive gap (a preload sweep).

    Returns
    -------
    divisor : ndarray
        Per point of the dataset: plotted value = SI value / divisor.
    xlabel, vlabel : str
        Labels of the displacement and of the velocity ``d/dτ`` (``τ = ωt``).
    """
    if physical is None:
        physical = not use_gap_scale(ds, points)
    if physical:
        return (np.full(ds.sizes["point"], 1e-6), "$x_1$ (\u00b5m)",
                "$x_1' = \\dot{x}_1/\\omega$ (\u00b5m)")
    return (length_scales(ds), "$X_1 = x_1/\\Delta$", "$X_1' = \\dot{x}_1/(\\Delta\\,\\omega)$")


def point_title(ds, point: int, *, law: bool = True) -> str:
    """``"bilinear, γ = 8: chaos (λ = 0.18 /T)"``: law, field values and classification."""
    parts = []
    if law and "law" in ds:
        parts.append(law_name(str(ds["law"].values[point])))
    for f in fields_of(ds):
        v = float(ds[f"param_{f}"].values[point])
        if np.isfinite(v):
            parts.append(format_field(f, v))
    head = ", ".join(parts)
    code = int(motion_codes(ds)[point])
    cls = code_label(code)
    if code > FAILED and "lyapunov" in ds:
        lam = float(ds["lyapunov"].values[point])
        if np.isfinite(lam):
            cls += f" (\u03bb = {lam:.3g} /T)"
    return f"{head}: {cls}" if head else cls


def midpoint_edges(values, log: bool = False) -> np.ndarray:
    """Cell edges around sorted-or-reversed centres (geometric midpoints when ``log``)."""
    v = np.asarray(values, dtype=float)
    if len(v) == 1:
        return np.array([v[0] * 0.9, v[0] * 1.1]) if log else np.array([v[0] - 0.5, v[0] + 0.5])
    if log:
        lv = np.log(v)
        mid = (lv[1:] + lv[:-1]) / 2
        return np.exp(np.concatenate([[2 * lv[0] - mid[0]], mid, [2 * lv[-1] - mid[-1]]]))
    mid = (v[1:] + v[:-1]) / 2
    return np.concatenate([[2 * v[0] - mid[0]], mid, [2 * v[-1] - mid[-1]]])


def sweep_is_log(ds, field: str) -> bool:
    """Whether the study spaces ``field`` logarithmically."""
    ax = study_of(ds).get("sweep", {}).get(field) or {}
    return bool(ax.get("log"))


def default_field(ds, field: str | None) -> str:
    """``field`` checked against the dataset, or its first swept field."""
    fields = fields_of(ds)
    if not fields:
        raise ValueError("the result has no swept field")
    if field is None:
        return fields[0]
    if field not in fields:
        raise ValueError(f"{field!r} is not a field of this result; it has {', '.join(fields)}")
    return field


def study_heading(ds, kind: str = "") -> str:
    """Figure heading: the study's title, else ``"<name>: <kind>"``."""
    st = study_of(ds)
    if st.get("title"):
        return st["title"]
    return ": ".join(p for p in (st.get("name") or "", kind) if p)
