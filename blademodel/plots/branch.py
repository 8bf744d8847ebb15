"""A continued branch: amplitude against the field, stable solid, unstable dashed, bifurcations marked."""

from __future__ import annotations

import numpy as np

from matplotlib.figure import Figure

from ..orbits.branch_states import alike, envelope, state_indices

#: Marker of each kind of special point.
MARKERS = {"fold": ("s", "fold"), "period-doubling": ("D", "period doubling"),
           "neimark-sacker": ("^", "Neimark-Sacker"), "grazing": ("o", "grazing"),
           "nonsmooth-fold": ("P", "nonsmooth fold"), "border-collision": ("X", "border collision"),
           "gap": ("*", "gap (no orbit found)"), "branch-point": ("v", "branch point")}


def _between(value, x, y, k):
    """``y`` at ``value`` on the segment from point ``k`` to ``k + 1`` (either direction)."""
    k1 = min(k + 1, len(x) - 1)
    if x[k1] == x[k]:
        return y[k]
    s = min(max((value - x[k]) / (x[k1] - x[k]), 0.0), 1.0)
    return y[k] + s * (y[k1] - y[k])


def stability_runs(stable, gaps=()):
    """The branch's runs of segments drawn alike: ``(first point, last point, solid)`` each.

    The segment from point ``k`` to ``k + 1`` is solid where both its ends are stable and
    dashed otherwise; none is drawn from a point in ``gaps`` (no orbit was found beyond it).
    Each run is drawn as one line: a dash pattern restarts at every line, so segments drawn
    one by one, shorter than a dash (a dense branch), showed an unstable stretch solid.
    """
    runs = []
    for k in range(len(stable) - 1):
        if k in gaps:
            continue
        solid = bool(stable[k] and stable[k + 1])
        if runs and runs[-1][1] == k and runs[-1][2] == solid:   # goes on from the last run, drawn alike
            runs[-1] = (runs[-1][0], k + 1, solid)
        else:
            runs.append((k, k + 1, solid))
    return runs


#: The special points' markers' zorder: below the lines' (matplotlib's default 2), so that a stretch of the
#: branch between two nearby markers still shows whether it is stable.
MARKERS_UNDER_LINES = 1.9

#: Beyond this many grazing points on a branch (a mistuned ring's contacts graze one by one) their markers are small.
CROWDED = 40

#: Line colours of successive branches in one figure: (stable, unstable). The first four use the default colour
#: cycle; the others, a dark and a light tone of one hue each (matplotlib's tab20b), so that a figure with a branch,
#: its period-doubled branches and those crossing at its branch points (``blademodel continue --switch``) repeats
#: no colour up to ten branches.
COLOURS = [("C0", "C3"), ("C2", "C1"), ("C4", "C6"), ("C9", "C5"), ("C8", "C7"),
           ("#393b79", "#9c9ede"), ("#637939", "#b5cf6b"), ("#8c6d31", "#e7ba52"), ("#843c39", "#e7969c"),
           ("#7b4173", "#de9ed6")]


def branch_figure(branch, state: str = "x1", *, quantity: str = "harmonic", overlay=None, ax=None,
                  labels=None, values=None) -> Figure:
    """Forced-response or bifurcation plot of a :class:`~blademodel.orbits.Branch` (or several).

    Parameters
    ----------
    branch : Branch or list of Branch
        Several (a branch and those switched to at its period doublings) share the axes,
        each in its own colours.
    state : str
        The state plotted, or a pattern such as ``"x*"`` (every blade's ``x``): the largest
        of the states it matches at each point is drawn as one state would be, the smallest
        as a thin line unless they are alike throughout (a tuned ring's travelling waves)
        (:mod:`~blademodel.orbits.branch_states`; not for ``"section"``).
    quantity : {"harmonic", "amplitude", "section", "reduction"}
        First-harmonic amplitude (of the excitation frequency), half the peak-to-peak
        excursion over the orbit, the Poincare samples ``state(k T)`` (a bifurcation
        diagram: a period-2 orbit draws two curves), or the vibration reduction ``P_d`` in
        percent, given in ``values`` (``state`` then names what it sums, for the label).
    overlay : tuple of arrays, optional
        ``(values, amplitudes)`` of a brute-force sweep, drawn as dots.
    ax : matplotlib Axes, optional
        Draw into these axes (of a figure with several panels) instead of a new figure.
    labels : list of str, optional
        What each branch is, for the legend (default, with several: its period).
    values : list of ndarray, optional
        With ``quantity="reduction"``: each branch's ``P_d`` at its points
        (:func:`~blademodel.orbits.branch_reduction.branch_vibration_reduction`).
    """
    branches = list(branch) if isinstance(branch, (list, tuple)) else [branch]
    own = ax is None
    if own:
        fig = Figure(figsize=(7, 4.2))
        ax = fig.add_subplot()
    fig = ax.figure
    marked = set()
    if labels is not None and len(labels) != len(branches):
        raise ValueError(f"labels: one per branch ({len(branches)}), got {len(labels)}")
    several = False
    if quantity == "reduction" and (values is None or len(values) != len(branches)):
        raise ValueError("quantity 'reduction': give each branch's P_d in values")
    for j, (b, (c_stable, c_unstable)) in enumerate(zip(branches, COLOURS * len(branches))):
        idx = state_indices(b.state_names, state) if quantity != "reduction" else [0]
        several = len(idx) > 1
        if quantity == "reduction":
            curves = [np.asarray(values[j], dtype=float)]
        elif quantity == "section":
            if several:
                raise ValueError(f"state {state!r}: the Poincare samples are drawn for one state, and the pattern "
                                 f"matches {len(idx)}")
            curves = [b.sections[:, k, idx[0]] for k in range(b.sections.shape[1])]
        else:
            largest, smallest, _ = envelope(b.harmonics if quantity == "harmonic" else b.amplitudes, idx)
            curves = [largest]
            if several and not alike(largest, smallest).all():   # how far they spread: a thin line
                ax.plot(b.params, smallest, "-", color=c_stable, lw=0.7, alpha=0.8,
                        label=f"{labels[j] + ', ' if labels is not None else ''}smallest of {state}")
        y = curves[0]
        x = b.params
        stable = b.stable
        gaps = {p.index for p in b.special if p.kind == "gap"}   # no orbit was found there: no line
        for yc in curves:
            for first_point, last_point, solid in stability_runs(stable, gaps):
                ax.plot(x[first_point:last_point + 1], yc[first_point:last_point + 1], "-" if solid else "--",
                        color=c_stable if solid else c_unstable, lw=1.6)
        tag = f"{labels[j]}, " if labels is not None else f"period {b.periods}, " if len(branches) > 1 else ""
        tag += f"largest of {state}, " if several else ""
        ax.plot([], [], "-", color=c_stable, label=f"{tag}stable")
        ax.plot([], [], "--", color=c_unstable, label=f"{tag}unstable")
        for kind, (marker, label) in MARKERS.items():
            pts = [p for p in b.special if p.kind == kind]
            if pts:
                yy = [_between(p.param, x, y, p.index) for p in pts]
                crowded = kind == "grazing" and len(pts) > CROWDED   # small, so that the curve stays visible
                ax.plot([p.param for p in pts], yy, marker, color="k", ms=3 if crowded else 7,
                        mfc="none" if kind == "grazing" else "k", mew=0.6 if crowded else 1.0,
                        label=None if kind in marked else label, zorder=MARKERS_UNDER_LINES)
                marked.add(kind)
    if overlay is not None:
        ax.plot(overlay[0], overlay[1], ".", color="0.5", ms=3, label="integration")
    what = {"harmonic": "first-harmonic amplitude", "amplitude": "amplitude", "section": "Poincare samples",
            "reduction": "vibration reduction P_d"}[quantity]
    first = branches[0]
    ax.set_xlabel(first.field)
    unit = ", %" if quantity == "reduction" else ""
    ax.set_ylabel(f"{what} of {state}{unit}" if not several else f"{what}, largest of {state}")
    periods = sorted({b.periods for b in branches})
    unfinished = " (unfinished: " + first.message + ")" if not first.complete else ""
    ax.set_title(f"period-{'/'.join(str(p) for p in periods)} orbits continued in {first.field}{unfinished}")
    ax.legend(loc="best", fontsize=8)
    ax.grid(alpha=0.3)
    if own:
        fig.tight_layout()
    return fig
