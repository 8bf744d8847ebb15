"""Case figures: time history, spectrum, Poincaré map and phase portrait of one point.

The four panels the paper shows for each case (its Figs 7, 8, 11, 12, 15, 16):
(a) the time history of ``X1 = x1 / Δ`` against ``t / T``, (b) the amplitude
spectrum of ``X1`` against ``f / f_e``, (c) the Poincaré map ``X1`` against
``X1' = dX1/dτ`` (``τ = ωt``) sampled at ``t = nT`` and (d) the phase portrait
``X1`` against ``X1'``. Where a point has no positive gap (a preload), ``x1`` is
shown in µm instead.
"""

from __future__ import annotations

import textwrap

import numpy as np
from matplotlib.figure import Figure

from ..analysis.spectrum import amplitude_spectrum
from .common import (FAILED, NOT_RUN, code_label, displacement, errors, excitation_omega, law_name, laws_of,
                     motion_codes, point_title, steps_per_period, study_heading)

#: Upper limit of the spectrum's ``f / f_e`` axis.
SPECTRUM_MAX_RATIO = 4.0

_PANEL_TITLES = ("time history", "amplitude spectrum", "Poincar\u00e9 map", "phase portrait")


def _history(ds, point: int):
    """``(t, x1, vx1)`` of the point's time history (finite samples), or ``None``."""
    if "history_x1" not in ds:
        return None
    t = np.asarray(ds["history_t"].values[point], dtype=float)
    x = np.asarray(ds["history_x1"].values[point], dtype=float)
    v = np.asarray(ds["history_vx1"].values[point], dtype=float)
    ok = np.isfinite(t) & np.isfinite(x) & np.isfinite(v)
    if ok.sum() < 2:
        return None
    return t[ok], x[ok], v[ok]


def _note(ax, text: str) -> None:
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", fontsize=9, color="0.35",
            wrap=True)
    ax.set_xticks([])
    ax.set_yticks([])


def _poincare_limits(ax, px, pv, orbit) -> None:
    """Limits of the Poincaré panel: the samples with a margin, never narrower than
    a few percent of the orbit (so a period-n map shows n clean points, not the
    round-off scatter of one point)."""
    ax.ticklabel_format(useOffset=False)
    if len(px) == 0:
        return
    for lim, p, o in ((ax.set_xlim, px, None if orbit is None else orbit[0]),
                      (ax.set_ylim, pv, None if orbit is None else orbit[1])):
        ref = np.ptp(o) if o is not None and np.ptp(o) > 0 else max(np.max(np.abs(p)), 1e-12)
        span = max(np.ptp(p), 0.1 * ref)
        mid = (p.max() + p.min()) / 2
        lim(mid - 0.6 * span, mid + 0.6 * span)


def draw_case(axes, ds, point: int, *, physical: bool | None = None, tag: str = "") -> None:
    """Draw the four case panels of ``point`` into ``axes``.

    Parameters
    ----------
    axes : sequence of 4 matplotlib Axes
        Time history, spectrum, Poincaré map, phase portrait.
    ds : xarray.Dataset
        A result (see :func:`blademodel.sweep.open_result`).
    point : int
        Index along the ``point`` dimension.
    physical : bool, optional
        Show ``x1`` in µm rather than ``X1 = x1 / Δ`` (default: only when the
        point has no positive gap).
    tag : str
        Prefix of the panel letters (e.g. ``"1"`` gives ``(1a)``).

    Notes
    -----
    Artists carry ``gid`` values ``"history"``, ``"spectrum"``, ``"poincare"``
    and ``"phase"`` so they can be found again (tests).
    """
    ax_t, ax_f, ax_p, ax_ph = axes
    for ax, letter, name in zip(axes, "abcd", _PANEL_TITLES):
        ax.set_title(f"({tag}{letter}) {name}", fontsize=10, loc="left")
    code = int(motion_codes(ds)[point])
    if code in (FAILED, NOT_RUN):
        msg = errors(ds)[point] if code == FAILED else "point not run yet"
        for ax in axes:
            _note(ax, "\n".join(textwrap.wrap(msg, 40)) or code_label(code))
        return
    div, xlab, vlab = displacement(ds, [point], physical)
    scale = float(div[point])
    omega = excitation_omega(ds, point)
    T = 2 * np.pi / omega

    # (c) Poincare map from the stored samples
    px = np.asarray(ds["poincare_x1"].values[point], dtype=float)
    pv = np.asarray(ds["poincare_vx1"].values[point], dtype=float)
    ok = np.isfinite(px) & np.isfinite(pv)
    px, pv = px[ok] / scale, pv[ok] / (scale * omega)
    ax_p.scatter(px, pv, s=14 if len(np.unique(np.round(px, 9))) < 20 else 4, color="C3", zorder=3,
                 gid="poincare", label="$t = nT$")
    ax_p.set_xlabel(xlab)
    ax_p.set_ylabel(vlab)

    hist = _history(ds, point)
    _poincare_limits(ax_p, px, pv, None if hist is None else (hist[1] / scale, hist[2] / (scale * omega)))
    if hist is None:
        for ax in (ax_t, ax_f, ax_ph):
            _note(ax, "no time history stored\n(run.history_periods = 0)")
        return
    t, x, v = hist
    X, V = x / scale, v / (scale * omega)
    S = steps_per_period(ds)

    # (a) time history
    ax_t.plot(t / T, X, lw=0.8, color="C0", gid="history")
    ax_t.set_xlabel("$t/T$")
    ax_t.set_ylabel(xlab)
    ax_t.set_xlim(t[0] / T, t[-1] / T)

    # (b) amplitude spectrum, without the mean (k = 0)
    try:
        ratio, amp = amplitude_spectrum(X, S)
    except ValueError as e:
        _note(ax_f, str(e))
    else:
        keep = (ratio > 0) & (ratio <= SPECTRUM_MAX_RATIO + 1e-9)
        ax_f.vlines(ratio[keep], 0, amp[keep], color="C0", lw=1.4, gid="spectrum")
        ax_f.set_xlim(0, SPECTRUM_MAX_RATIO + 0.08)
        ax_f.set_ylim(0, (amp[keep].max() if keep.any() else 1) * 1.1 or 1)
        ax_f.set_xticks(np.arange(0, SPECTRUM_MAX_RATIO + 0.5, 0.5))
        ax_f.set_xlabel("$f/f_e$")
        ax_f.set_ylabel("amplitude of $x_1$ (\u00b5m)" if "\u00b5m" in xlab else "amplitude of $X_1$")

    # (d) phase portrait, with the history's own t = nT points
    ax_ph.plot(X, V, lw=0.6, color="C0", gid="phase")
    ax_ph.scatter(X[::S], V[::S], s=10, color="C3", zorder=3, label="$t = nT$")
    ax_ph.set_xlabel(xlab)
    ax_ph.set_ylabel(vlab)


def case_figure(ds, point: int, *, physical: bool | None = None) -> Figure:
    """The paper's four case panels for one point of a result, as a 2 x 2 figure.

    Parameters
    ----------
    ds : xarray.Dataset
        A result (see :func:`blademodel.sweep.open_result`).
    point : int
        Index along the ``point`` dimension.
    physical : bool, optional
        Show ``x1`` in µm rather than ``X1 = x1 / Δ``.

    Returns
    -------
    matplotlib.figure.Figure
        Axes in the order time history, spectrum, Poincaré map, phase portrait;
        the title names the law, the field values and the classification.
    """
    n = ds.sizes["point"]
    if not -n <= point < n:
        raise ValueError(f"point {point} out of range: the result has {n} points")
    point = point % n
    fig = Figure(figsize=(10, 7.5), layout="constrained")
    axes = fig.subplots(2, 2).ravel()
    draw_case(axes, ds, point, physical=physical)
    fig.suptitle(point_title(ds, point), fontsize=12)
    return fig


def cases_figure(ds, *, law: str | None = None, physical: bool | None = None) -> Figure:
    """Every case point of a result (or of one law), one row of four panels each.

    Parameters
    ----------
    ds : xarray.Dataset
        A result (see :func:`blademodel.sweep.open_result`).
    law : str, optional
        Only the points of this friction law.
    physical : bool, optional
        Show ``x1`` in µm rather than ``X1 = x1 / Δ``.

    Returns
    -------
    matplotlib.figure.Figure
        ``4 * n_points`` axes, row by row; each row titled with its point.
    """
    laws = np.asarray(ds["law"].values).astype(str)
    if law is not None and law not in laws:
        raise ValueError(f"no points with law {law!r}; the result has {', '.join(laws_of(ds))}")
    pts = [i for i in range(ds.sizes["point"]) if law is None or laws[i] == law]
    fig = Figure(figsize=(15, 3.3 * len(pts) + 0.6), layout="constrained")
    rows = fig.subfigures(len(pts), 1, squeeze=False)[:, 0]
    for r, (sub, i) in enumerate(zip(rows, pts)):
        axes = sub.subplots(1, 4, gridspec_kw={"width_ratios": [1.5, 1.1, 1, 1]})
        draw_case(axes, ds, i, physical=physical, tag=str(r + 1) if len(pts) > 1 else "")
        sub.suptitle(point_title(ds, i, law=law is None), fontsize=11, x=0.01,
                     ha="left")
    head = study_heading(ds, "cases")
    if law is not None:
        head = f"{head} \u2014 {law_name(law)}" if head else law_name(law)
    if head:
        fig.suptitle(head, fontsize=13)
    return fig
