"""Periodicity maps: the motion class over a two-field sweep, as a discrete colour map."""

from __future__ import annotations

import numpy as np
from matplotlib.cm import ScalarMappable
from matplotlib.colors import BoundaryNorm, ListedColormap, to_rgb
from matplotlib.figure import Figure

from .common import (FAILED, NOT_RUN, code_label, field_axis, fields_of, law_name, laws_of,
                     midpoint_edges, motion_codes, study_heading, study_of, sweep_is_log)

#: Colour of every motion code: period-1..8 distinct hues, 9..16 a dark-green ramp,
#: then the non-periodic classes, failed and not-run points.
CODE_COLORS = {
    1: "#4c72b0", 2: "#55a868", 3: "#8172b2", 4: "#ccb974", 5: "#64b5cd", 6: "#8c613c", 7: "#da8bc3",
    8: "#9ecae1", 9: "#c7e9c0", 10: "#a1d99b", 11: "#74c476", 12: "#41ab5d", 13: "#238b45", 14: "#006d2c",
    15: "#00441b", 16: "#002b11",
    -1: "#f0a330", -2: "#c44e52", 0: "#9a9a9a", FAILED: "#000000", NOT_RUN: "#ffffff",
}


def _colour(code: int) -> str:
    """Colour of a motion code (codes above 16 cannot occur; they get a dark green)."""
    return CODE_COLORS.get(int(code), "#003300")


def _grid(ds, sel: np.ndarray, f1: str, f2: str):
    """Unique values of both fields (in sweep order) and the code grid ``[i2, i1]`` of ``sel``."""
    a = np.asarray(ds[f"param_{f1}"].values, dtype=float)[sel]
    b = np.asarray(ds[f"param_{f2}"].values, dtype=float)[sel]
    ua = np.asarray(list(dict.fromkeys(a.tolist())))
    ub = np.asarray(list(dict.fromkeys(b.tolist())))
    grid = np.full((len(ub), len(ua)), NOT_RUN, dtype=int)
    codes = motion_codes(ds)[sel]
    for va, vb, c in zip(a, b, codes):
        grid[np.flatnonzero(ub == vb)[0], np.flatnonzero(ua == va)[0]] = c
    return ua, ub, grid


def _sorted(values, grid, axis):
    order = np.argsort(values, kind="stable")
    return values[order], np.take(grid, order, axis=axis)


def periodicity_map_figure(ds, *, annotate: bool | None = None) -> Figure:
    """Motion class over a 2-D sweep, one panel per friction law.

    Parameters
    ----------
    ds : xarray.Dataset
        A result of a sweep over two fields (see
        :func:`blademodel.sweep.open_result`).
    annotate : bool, optional
        Write the class label in every cell (default: when a panel has at most
        150 cells).

    Returns
    -------
    matplotlib.figure.Figure
        The first field on the horizontal axis, the second on the vertical one.
        Each panel holds one ``QuadMesh`` (``gid="map:<law>"``) whose array,
        of shape ``(n_field2, n_field1)`` in increasing field order, holds the
        motion codes: ``n`` period-n, ``0`` nonperiodic, ``-1`` quasi-periodic,
        ``-2`` chaos, ``-3`` failed, ``-4`` not run. The colour bar names them.

    Raises
    ------
    ValueError
        If the result is not a sweep over two fields.
    """
    fields = fields_of(ds)
    if len(fields) != 2 or _is_cases(ds):
        raise ValueError(f"a periodicity map needs a sweep over two fields; this result has {fields}")
    f1, f2 = fields
    laws = laws_of(ds)
    law_of = np.asarray(ds["law"].values).astype(str)
    factor1, factor2 = field_axis(f1)[1], field_axis(f2)[1]
    log1, log2 = sweep_is_log(ds, f1), sweep_is_log(ds, f2)
    shown = sorted(set(motion_codes(ds).tolist()))
    cmap = ListedColormap([_colour(c) for c in shown])
    # Discrete colours on the codes themselves: each present code has its own bin.
    mids = [(a + b) / 2 for a, b in zip(shown[:-1], shown[1:])]
    norm = BoundaryNorm([shown[0] - 0.5, *mids, shown[-1] + 0.5], cmap.N)

    fig = Figure(figsize=(1.2 + 5.2 * len(laws), 4.8), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, len(laws), squeeze=False, sharey=True)[0])
    for ax, law in zip(axes, laws):
        ua, ub, grid = _grid(ds, law_of == law, f1, f2)
        ua, grid = _sorted(ua, grid, 1)
        ub, grid = _sorted(ub, grid, 0)
        xe = midpoint_edges(ua * factor1, log=log1)
        ye = midpoint_edges(ub * factor2, log=log2)
        ax.pcolormesh(xe, ye, grid, cmap=cmap, norm=norm, edgecolors="w", linewidth=0.3, gid=f"map:{law}")
        if annotate if annotate is not None else grid.size <= 150:
            xc, yc = ua * factor1, ub * factor2
            for j in range(grid.shape[0]):
                for i in range(grid.shape[1]):
                    code = int(grid[j, i])
                    r, g, b = to_rgb(_colour(code))
                    ink = "k" if 0.299 * r + 0.587 * g + 0.114 * b > 0.55 else "w"
                    ax.text(xc[i], yc[j], code_label(code).replace("quasi-periodic", "QP").replace(
                        "nonperiodic", "NP").replace("not run", ""), ha="center", va="center",
                        fontsize=9 if grid.size <= 40 else 7,
                        color=ink)
        if log1:
            ax.set_xscale("log")
        if log2:
            ax.set_yscale("log")
        ax.set_xlabel(field_axis(f1)[0])
        ax.set_title(f"{law_name(law)} friction" if law != "none" else law_name(law), fontsize=10, loc="left")
    axes[0].set_ylabel(field_axis(f2)[0])
    sm = ScalarMappable(norm=norm, cmap=cmap)
    cb = fig.colorbar(sm, ax=list(axes), ticks=shown, fraction=0.04, aspect=30, pad=0.02)
    cb.ax.set_yticklabels([code_label(c) for c in shown])
    cb.ax.minorticks_off()
    cb.ax.tick_params(labelsize=8)
    cb.ax.set_title("motion", fontsize=9, loc="left")
    fig.suptitle(study_heading(ds, "periodicity map"), fontsize=12)
    return fig


def _is_cases(ds) -> bool:
    """Whether the result is a set of case points rather than a sweep."""
    return bool(study_of(ds).get("cases"))
