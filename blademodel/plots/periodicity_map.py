"""Periodicity maps: the motion class over a two-field sweep, as a discrete colour map."""

from __future__ import annotations

import numpy as np
from matplotlib.colors import BoundaryNorm, ListedColormap, to_rgb
from matplotlib.figure import Figure

from .common import (FAILED, NOT_RUN, code_label, field_axis, fields_of, law_name, laws_of,
                     midpoint_edges, motion_codes, study_heading, sweep_is_log)

#: Colour of every motion code: period-1..8 distinct hues, 9..16 a dark-green ramp,
#: then the non-periodic classes, failed and not-run points.
CODE_COLORS = {
    1: "#4c72b0", 2: "#55a868", 3: "#8172b2", 4: "#ccb974", 5: "#64b5cd", 6: "#8c613c", 7: "#da8bc3",
    8: "#9ecae1", 9: "#c7e9c0", 10: "#a1d99b", 11: "#74c476", 12: "#41ab5d", 13: "#238b45", 14: "#006d2c",
    15: "#00441b", 16: "#002b11",
    -1: "#f0a330", -2: "#c44e52", 0: "#9a9a9a", FAILED: "#000000", NOT_RUN: "#ffffff",
}

#: Order of the classes in the colour bar (bottom to top).
CODE_ORDER = [NOT_RUN, FAILED, 0, -2, -1] + list(range(1, 17))


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
    if len(fields) != 2 or study_of_cases(ds):
        raise ValueError(f"a periodicity map needs a sweep over two fields; this result has {fields}")
    f1, f2 = fields
    laws = laws_of(ds)
    law_of = np.asarray(ds["law"].values).astype(str)
    factor1, factor2 = field_axis(f1)[1], field_axis(f2)[1]
    log1, log2 = sweep_is_log(ds, f1), sweep_is_log(ds, f2)
    present = set(motion_codes(ds).tolist())
    present = {c if c <= 16 else 16 for c in present}
    shown = [c for c in CODE_ORDER if c in present]
    cmap = ListedColormap([CODE_COLORS[c] for c in shown])
    # Discrete colours on the codes themselves: each code falls in its own bin.
    bounds = np.arange(len(shown) + 1) - 0.5
    norm = BoundaryNorm(bounds, cmap.N)
    rank = {c: i for i, c in enumerate(shown)}

    fig = Figure(figsize=(1.2 + 5.2 * len(laws), 4.8), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, len(laws), squeeze=False, sharey=True)[0])
    mesh = None
    for ax, law in zip(axes, laws):
        ua, ub, grid = _grid(ds, law_of == law, f1, f2)
        ua, grid = _sorted(ua, grid, 1)
        ub, grid = _sorted(ub, grid, 0)
        xe = midpoint_edges(ua * factor1, log=log1)
        ye = midpoint_edges(ub * factor2, log=log2)
        clipped = np.where(grid > 16, 16, grid)
        colour_index = np.vectorize(rank.get)(clipped)
        mesh = ax.pcolormesh(xe, ye, grid, cmap=cmap, norm=norm, edgecolors="w", linewidth=0.3, gid=f"map:{law}")
        # the QuadMesh keeps the codes as its data; colours come from their ranks
        mesh.set_array(grid)
        mesh.set_facecolor(cmap(norm(colour_index)).reshape(-1, 4))
        mesh.update_scalarmappable = lambda *a, **k: None  # keep the explicit face colours
        if annotate if annotate is not None else grid.size <= 150:
            xc, yc = ua * factor1, ub * factor2
            for j in range(grid.shape[0]):
                for i in range(grid.shape[1]):
                    code = int(grid[j, i])
                    r, g, b = to_rgb(CODE_COLORS[min(code, 16)])
                    ink = "k" if 0.299 * r + 0.587 * g + 0.114 * b > 0.55 else "w"
                    ax.text(xc[i], yc[j], code_label(code).replace("quasi-periodic", "QP").replace(
                        "nonperiodic", "NP").replace("not run", ""), ha="center", va="center", fontsize=7,
                        color=ink)
        if log1:
            ax.set_xscale("log")
        if log2:
            ax.set_yscale("log")
        ax.set_xlabel(field_axis(f1)[0])
        ax.set_title(f"{law_name(law)} friction" if law != "none" else law_name(law), fontsize=10, loc="left")
    axes[0].set_ylabel(field_axis(f2)[0])
    sm = _Mappable(cmap, norm)
    cb = fig.colorbar(sm, ax=list(axes), ticks=np.arange(len(shown)), fraction=0.05, pad=0.02)
    cb.ax.set_yticklabels(["P>15" if c == 16 and any(v > 16 for v in motion_codes(ds)) else code_label(c)
                           for c in shown])
    cb.ax.tick_params(labelsize=8)
    cb.set_label("motion")
    head = study_heading(ds)
    fig.suptitle(f"{head}: periodicity map" if head else "periodicity map", fontsize=12)
    return fig


def study_of_cases(ds) -> bool:
    """Whether the result is a set of case points rather than a sweep."""
    from .common import study_of
    return bool(study_of(ds).get("cases"))


def _Mappable(cmap, norm):
    from matplotlib.cm import ScalarMappable
    sm = ScalarMappable(norm=norm, cmap=cmap)
    sm.set_array([])
    return sm
