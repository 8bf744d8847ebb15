"""Vibration reduction curves: ``P_d`` (%) against a swept field, the laws overlaid."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from .common import (default_field, field_axis, field_values, fields_of, format_field, law_name, laws_of,
                     study_heading, sweep_is_log)

_MARKERS = "osD^v<>ph"


def has_reduction(ds) -> bool:
    """Whether the result holds any finite ``P_d``."""
    return "Pd" in ds and bool(np.isfinite(np.asarray(ds["Pd"].values, dtype=float)).any())


def reduction_figure(ds, field: str | None = None) -> Figure:
    """``P_d`` against ``field`` with one curve per friction law.

    Parameters
    ----------
    ds : xarray.Dataset
        A result computed with ``run.vibration_reduction`` (see
        :func:`blademodel.sweep.open_result`).
    field : str, optional
        Swept field on the horizontal axis (default: the first). With a 2-D
        sweep there is one curve per law and value of the other field.

    Returns
    -------
    matplotlib.figure.Figure
        One axes; each curve is a ``Line2D`` with ``gid="Pd:<law>"`` (plus
        ``:<other field value>`` for a 2-D sweep), points in increasing field
        order, NaN where a point failed or did not run; the zero line has
        ``gid="zero"``.

    Raises
    ------
    ValueError
        If the result has no ``P_d`` (``run.vibration_reduction`` was off).
    """
    if not has_reduction(ds):
        raise ValueError("the result has no vibration reduction P_d (run with run.vibration_reduction: true)")
    field = default_field(ds, field)
    others = [f for f in fields_of(ds) if f != field]
    law_of = np.asarray(ds["law"].values).astype(str)
    xv = field_values(ds, field)
    pd = np.asarray(ds["Pd"].values, dtype=float)
    xlab, _ = field_axis(field)

    fig = Figure(figsize=(7.5, 4.8), layout="constrained")
    ax = fig.add_subplot()
    ax.axhline(0, color="0.4", lw=0.8, zorder=1, gid="zero")
    for k, law in enumerate(laws_of(ds)):
        sel = law_of == law
        groups = [((), sel)]
        if others:
            ov = np.asarray(ds[f"param_{others[0]}"].values, dtype=float)
            groups = [((v,), sel & (ov == v)) for v in np.unique(ov[sel])]
        for g, (key, mask) in enumerate(groups):
            idx = np.flatnonzero(mask)
            idx = idx[np.argsort(xv[idx], kind="stable")]
            label = law_name(law) + (f", {format_field(others[0], key[0])}" if key else "")
            gid = f"Pd:{law}" + (f":{key[0]:g}" if key else "")
            ax.plot(xv[idx], pd[idx], marker=_MARKERS[k % len(_MARKERS)], ms=4, lw=1.4,
                    color=f"C{k}" if not key else None, alpha=1 if not key else 0.5 + 0.5 * (g + 1) / len(groups),
                    label=label, gid=gid, zorder=3)
    if sweep_is_log(ds, field):
        ax.set_xscale("log")
    ax.set_xlabel(xlab)
    ax.set_ylabel("vibration reduction $P_d$ (%)")
    ax.grid(alpha=0.3)
    ax.legend(title="friction law", fontsize=9)
    fig.suptitle(study_heading(ds, "vibration reduction"), fontsize=12)
    return fig
