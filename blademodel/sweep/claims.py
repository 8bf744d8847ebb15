"""A study's claims beside its measurements: what a source reports at a point, what blademodel finds there.

A :class:`~blademodel.sweep.spec.Claim` names a point of a study (``at``) and the
motion reported there. :func:`check_claims` finds the point in a result file (the
case itself, or the nearest grid point of a sweep) and returns one row per claim:
the claim, the measured motion, its largest Lyapunov exponent, ``P_d`` when the
study computed it, and whether the two agree. ``blademodel reproduce`` prints
these rows and writes them to ``summary.json``; the reproduction report's table is
built from the same rows (``docs/tools/reproduction_tables.py``).
"""

from __future__ import annotations

import math

import numpy as np

from .point import motion_label
from .spec import Study


def _distance(values: np.ndarray, target: float) -> np.ndarray:
    """Relative distance of ``values`` to ``target`` (absolute when the target is 0)."""
    return np.abs(values - target) / (abs(target) if target else 1.0)


def _finite(x) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def check_claims(study: Study, ds) -> list[dict]:
    """One row per claim of ``study``, measured in the result ``ds`` (from :func:`~blademodel.sweep.open_result`).

    Returns
    -------
    list of dict
        ``study``, ``law``, ``at`` (the claimed point), ``point`` (the point
        measured: the nearest one of the study's grid), ``paper`` (the claimed
        motion), ``measured`` (the motion found, ``failed: ...`` or ``not run``),
        ``lyapunov`` (per excitation period, or None), ``P_d`` (percent, or None)
        and ``agrees`` (None when nothing was measured).
    """
    laws = np.asarray([str(v) for v in ds["law"].values])
    rows = []
    for claim in study.claims:
        law = claim.law or str(laws[0])
        candidates = np.flatnonzero(laws == law)
        distance = np.zeros(len(candidates))
        for field, target in claim.at.items():
            distance = np.maximum(distance, _distance(ds[f"param_{field}"].values[candidates], target))
        i = int(candidates[np.argmin(distance)])
        row = {"study": study.name, "law": law, "at": dict(claim.at),
               "point": {f: float(ds[f"param_{f}"].values[i]) for f in claim.at},
               "paper": claim.motion, "lyapunov": None, "P_d": None}
        error = str(ds["error"].values[i])
        if not bool(ds["done"].values[i]):
            row["measured"], row["agrees"] = "not run", None
        elif error:
            row["measured"], row["agrees"] = "failed: " + error.splitlines()[0], None
        else:
            row["measured"] = motion_label(int(ds["motion"].values[i]))
            row["agrees"] = row["measured"] == claim.motion
            row["lyapunov"] = _finite(ds["lyapunov"].values[i])
            if "Pd" in ds:
                row["P_d"] = _finite(ds["Pd"].values[i])
        rows.append(row)
    return rows


def tally(rows: list[dict]) -> tuple[int, int]:
    """``(agree, measured)``: how many claims the measurements confirm, of those measured."""
    measured = [r for r in rows if r["agrees"] is not None]
    return sum(r["agrees"] for r in measured), len(measured)


def _point(row: dict) -> str:
    text = ", ".join(f"{f} = {v:g}" for f, v in row["point"].items())
    if any(not math.isclose(row["point"][f], v, rel_tol=1e-9) for f, v in row["at"].items()):
        text += " (nearest to " + ", ".join(f"{v:g}" for v in row["at"].values()) + ")"
    return text


def claims_table(rows: list[dict]) -> list[str]:
    """The rows as aligned text lines, with the tally last."""
    head = ("study", "law", "point", "paper", "measured", "lambda/T", "P_d %", "agrees")
    body = [(r["study"], r["law"], _point(r), r["paper"], r["measured"],
             "" if r["lyapunov"] is None else f"{r['lyapunov']:+.3f}",
             "" if r["P_d"] is None else f"{r['P_d']:.1f}",
             {True: "yes", False: "no", None: "-"}[r["agrees"]]) for r in rows]
    widths = [max(len(str(x)) for x in col) for col in zip(head, *body)]
    lines = ["  ".join(str(x).ljust(w) for x, w in zip(line, widths)).rstrip() for line in (head, *body)]
    agree, measured = tally(rows)
    lines.append(f"{agree} of {measured} measured claims agree with the paper"
                 + (f" ({len(rows) - measured} not measured)" if measured < len(rows) else ""))
    return lines
