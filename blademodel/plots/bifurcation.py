"""Bifurcation diagrams: the Poincaré samples of ``X1`` against a swept field."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.transforms import blended_transform_factory

from .common import (FAILED, NOT_RUN, default_field, displacement, field_axis, field_values, law_name, laws_of,
                     midpoint_edges, motion_codes, study_heading, sweep_is_log)

#: Background shading of the non-periodic motion classes (code: colour, label).
SHADES = {-2: ("#f8d3cf", "chaos"), -1: ("#fde6c2", "quasi-periodic"), 0: ("#e6e6e6", "nonperiodic")}


def _shade(ax, x, codes, log: bool, grid) -> set:
    """Shade the cells around the points of a non-periodic class; return the classes shown.

    ``grid`` holds every field value of the panel (run or not): the cells end
    half-way to the neighbouring values.
    """
    order = np.argsort(x)
    xs, cs = x[order], codes[order]
    keep = np.isfinite(xs)
    xs, cs = xs[keep], cs[keep]
    if len(xs) == 0:
        return set()
    grid = np.unique(np.asarray(grid, dtype=float)[np.isfinite(grid)])
    edges = midpoint_edges(grid, log=log and np.all(grid > 0))
    shown = set()
    for j, v in enumerate(grid):
        here = set(cs[xs == v].tolist())
        for code in (-2, -1, 0):  # the most irregular class of the points at this value wins
            if code in here:
                ax.axvspan(edges[j], edges[j + 1], color=SHADES[code][0], lw=0, zorder=0)
                shown.add(code)
                break
    return shown


def bifurcation_figure(ds, field: str | None = None, *, physical: bool | None = None,
                       shade: bool = True) -> Figure:
    """Bifurcation diagram of a result: Poincaré samples of ``X1`` against ``field``.

    Parameters
    ----------
    ds : xarray.Dataset
        A result (see :func:`blademodel.sweep.open_result`).
    field : str, optional
        Swept field on the horizontal axis (default: the first). With a 2-D
        sweep the points of every value of the other field share the axis.
    physical : bool, optional
        ``True``: ``x1`` in µm; ``False``: ``X1 = x1 / Δ`` (each point's own
        gap); default ``X1`` unless some point has no positive gap (preload).
    shade : bool
        Shade the background of chaotic, quasi-periodic and nonperiodic points.

    Returns
    -------
    matplotlib.figure.Figure
        One panel per friction law, stacked with a shared horizontal axis. The
        samples are a scatter collection with ``gid="poincare"``; failed points
        are red crosses at the bottom edge (``gid="failed"``).
    """
    field = default_field(ds, field)
    laws = laws_of(ds)
    law_of = np.asarray(ds["law"].values).astype(str)
    codes = motion_codes(ds)
    div, ylab, _ = displacement(ds, None, physical)
    xlab, _ = field_axis(field)
    xv = field_values(ds, field)
    log = sweep_is_log(ds, field)
    px = np.asarray(ds["poincare_x1"].values, dtype=float)
    n_samp = px.shape[1]

    fig = Figure(figsize=(8, 1.0 + 3.2 * len(laws)), layout="constrained")
    axes = np.atleast_1d(fig.subplots(len(laws), 1, sharex=True, squeeze=False)[:, 0])
    for ax, law in zip(axes, laws):
        sel = np.flatnonzero(law_of == law)
        ran = sel[codes[sel] > FAILED]
        shown = _shade(ax, xv[ran], codes[ran], log, xv[sel]) if shade else set()
        x = np.repeat(xv[ran], n_samp)
        y = (px[ran] / div[ran, None]).ravel()
        ok = np.isfinite(x) & np.isfinite(y)
        n_x = max(len(np.unique(xv[ran])), 1)
        ax.scatter(x[ok], y[ok], s=float(np.clip(400 / n_x, 1.5, 6)), c="k", marker="o", lw=0, rasterized=len(x) > 20000, gid="poincare")
        failed = sel[codes[sel] == FAILED]
        handles = [Patch(color=SHADES[c][0], label=SHADES[c][1]) for c in (-2, -1, 0) if c in shown]
        if len(failed):
            tr = blended_transform_factory(ax.transData, ax.transAxes)
            ax.scatter(xv[failed], np.full(len(failed), 0.02), transform=tr, marker="x", s=30, c="C3",
                       zorder=4, gid="failed", clip_on=False)
            handles.append(Line2D([], [], ls="", marker="x", color="C3", label="failed"))
        not_run = sel[codes[sel] == NOT_RUN]
        if len(not_run):
            handles.append(Line2D([], [], ls="", marker="|", color="0.6", label="not run"))
            tr = blended_transform_factory(ax.transData, ax.transAxes)
            ax.scatter(xv[not_run], np.full(len(not_run), 0.02), transform=tr, marker="|", s=30, c="0.6",
                       zorder=4, gid="not_run", clip_on=False)
        if handles:
            ax.legend(handles=handles, loc="lower right", bbox_to_anchor=(1.0, 1.0), ncol=len(handles), fontsize=8,
                      frameon=False, borderaxespad=0.1, handlelength=1.2)
        ax.set_ylabel(ylab)
        ax.set_title(f"{law_name(law)} friction" if law != "none" else law_name(law), fontsize=10, loc="left")
        if log:
            ax.set_xscale("log")
        if len(xv[sel]) and np.all(np.isfinite(xv[sel])):
            lo, hi = np.nanmin(xv[sel]), np.nanmax(xv[sel])
            if hi > lo:
                pad = 0.0 if shade else 0.02 * (hi - lo)
                edges = midpoint_edges(np.unique(xv[sel]), log=log and lo > 0)
                ax.set_xlim(edges[0] - pad, edges[-1] + pad)
    axes[-1].set_xlabel(xlab)
    fig.suptitle(study_heading(ds, "bifurcation diagram"), fontsize=12)
    return fig
