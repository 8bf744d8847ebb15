"""Finding the paper's studies (``models/studies``) and summarising their results."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..sweep.point import motion_label


def studies_dir() -> Path:
    """``$BLADEMODEL_STUDIES``, else ``models/studies`` in the working folder or the source tree."""
    candidates = [os.environ.get("BLADEMODEL_STUDIES"), Path.cwd() / "models" / "studies",
                  Path(__file__).resolve().parents[2] / "models" / "studies"]
    for c in candidates:
        if c and Path(c).is_dir():
            return Path(c)
    raise ValueError("cannot find models/studies: run from the blademodel checkout or set BLADEMODEL_STUDIES")


def paper_figures() -> dict[str, Path]:
    """``{"fig05": path, ...}`` for every paper figure study (``figNN.yaml``; not extensions
    such as ``fig17_iwan.yaml``)."""
    return {p.stem: p for p in sorted(studies_dir().glob("fig*.yaml")) if p.stem[3:].isdigit()}


def summarize(ds) -> list[dict]:
    """One row per point of a case study: law, values, motion, Lyapunov exponent, P_d."""
    rows = []
    for i in range(ds.sizes["point"]):
        row = {"law": str(ds["law"].values[i])}
        for f in ds.attrs["fields"]:
            v = float(ds[f"param_{f}"].values[i])
            if not np.isnan(v):
                row[f] = v
        err = str(ds["error"].values[i])
        if err:
            row["motion"] = "failed: " + err
        else:
            row["motion"] = motion_label(int(ds["motion"].values[i]))
            lam = float(ds["lyapunov"].values[i])
            row["lyapunov"] = None if np.isnan(lam) else lam
            row["events"] = int(ds["events"].values[i])
        rows.append(row)
    return rows
