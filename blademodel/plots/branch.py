"""A continued branch: amplitude against the field, stable solid, unstable dashed, bifurcations marked."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

#: Marker of each kind of special point.
MARKERS = {"fold": ("s", "fold"), "period-doubling": ("D", "period doubling"),
           "neimark-sacker": ("^", "Neimark-Sacker"), "grazing": ("o", "grazing")}


def _between(value, x, y, k):
    """``y`` at ``value`` on the segment from point ``k`` to ``k + 1`` (either direction)."""
    k1 = min(k + 1, len(x) - 1)
    if x[k1] == x[k]:
        return y[k]
    s = min(max((value - x[k]) / (x[k1] - x[k]), 0.0), 1.0)
    return y[k] + s * (y[k1] - y[k])


def branch_figure(branch, state: str = "x1", *, quantity: str = "harmonic", overlay=None) -> Figure:
    """Forced-response or bifurcation plot of a :class:`~blademodel.orbits.Branch`.

    Parameters
    ----------
    branch : Branch
    state : str
        The state plotted.
    quantity : {"harmonic", "amplitude"}
        First-harmonic amplitude, or half the peak-to-peak excursion over the orbit.
    overlay : tuple of arrays, optional
        ``(values, amplitudes)`` of a brute-force sweep, drawn as dots.
    """
    i = branch.state_names.index(state)
    y = np.abs(branch.harmonics[:, i]) if quantity == "harmonic" else branch.amplitudes[:, i]
    x = branch.params
    fig = Figure(figsize=(7, 4.2))
    ax = fig.add_subplot()
    stable = branch.stable
    for k in range(len(x) - 1):   # each segment drawn as its end points' stability: solid or dashed
        both = stable[k] and stable[k + 1]
        ax.plot(x[k:k + 2], y[k:k + 2], "-" if both else "--", color="C0" if both else "C3", lw=1.6)
    ax.plot([], [], "-", color="C0", label="stable")
    ax.plot([], [], "--", color="C3", label="unstable")
    for kind, (marker, label) in MARKERS.items():
        pts = [p for p in branch.special if p.kind == kind]
        if pts:
            yy = [_between(p.param, x, y, p.index) for p in pts]
            ax.plot([p.param for p in pts], yy, marker, color="k", ms=7, label=label)
    if overlay is not None:
        ax.plot(overlay[0], overlay[1], ".", color="0.5", ms=3, label="integration")
    what = "first-harmonic amplitude" if quantity == "harmonic" else "amplitude"
    ax.set_xlabel(branch.field)
    ax.set_ylabel(f"{what} of {state}")
    ax.set_title(f"period-{branch.periods} orbits continued in {branch.field}")
    ax.legend(loc="best", fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig
