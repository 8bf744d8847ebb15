"""Markdown tables of the reproduction report, from `blademodel reproduce` output folders.

    python docs/tools/reproduction_tables.py out/ [variant_folder ...]

Prints, for every study found: the motion classes along a bifurcation sweep (as
intervals of the swept field), the case points, and the P_d ranges, so that the
report quotes measured results only.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from blademodel.sweep import open_result
from blademodel.sweep.point import motion_label


def _labels(ds) -> list[str]:
    """Motion class of every point (``open_result`` derives it from the stored period and exponent)."""
    return ["failed" if err else "?" if not done else motion_label(int(code))
            for code, err, done in zip(ds["motion"].values, ds["error"].values, ds["done"].values)]


def intervals(ds) -> str:
    """Runs of equal motion class along a 1-D sweep: ``P1 [0.5, 7.3]; chaos [7.4, 8.0]; ...``."""
    field = ds.attrs["fields"][0]
    x = ds[f"param_{field}"].values
    labels = _labels(ds)
    order = np.argsort(x)
    runs, start = [], 0
    for i in range(1, len(order) + 1):
        if i == len(order) or labels[order[i]] != labels[order[start]]:
            runs.append(f"{labels[order[start]]} [{x[order[start]]:.3g}, {x[order[i - 1]]:.3g}]")
            start = i
    return "; ".join(runs)


def cases(ds) -> list[str]:
    rows, labels = [], _labels(ds)
    for i in range(ds.sizes["point"]):
        vals = ", ".join(f"{f} = {ds[f'param_{f}'].values[i]:g}" for f in ds.attrs["fields"]
                         if not np.isnan(ds[f"param_{f}"].values[i]))
        lam = float(ds["lyapunov"].values[i])
        rows.append(f"{ds['law'].values[i]}, {vals}: {labels[i]}"
                    + ("" if np.isnan(lam) else f" (λ = {lam:+.3f}/T)"))
    return rows


def reduction(ds) -> list[str]:
    field = ds.attrs["fields"][0]
    out = []
    for law in dict.fromkeys(ds["law"].values):
        sel = ds["law"].values == law
        x, pd = ds[f"param_{field}"].values[sel], ds["Pd"].values[sel]
        k = int(np.nanargmax(pd))
        out.append(f"{law}: P_d from {np.nanmin(pd):.1f} % to {np.nanmax(pd):.1f} % (max at {field} = {x[k]:g}); "
                   f"at the ends {pd[0]:.1f} % ({field} = {x[0]:g}) and {pd[-1]:.1f} % ({field} = {x[-1]:g})")
    return out


def main(folders: list[str]) -> None:
    for folder in folders:
        for path in sorted(Path(folder).glob("*/*.nc")):
            ds = open_result(path)
            study = ds.attrs["study"]
            print(f"### {study['name']}: {study['title']}\n")
            print(f"paper: {study.get('paper', '')}\n")
            if study["plot"] == "cases":
                print("\n".join(f"- {r}" for r in cases(ds)))
            elif study["plot"] == "reduction":
                print("\n".join(f"- {r}" for r in reduction(ds)))
            else:
                print(f"- {intervals(ds)}")
            print()


if __name__ == "__main__":
    main(sys.argv[1:])
