"""``blademodel plot RESULT.nc [--out DIR]``: write the figures of a result (a sweep or a branch) as PNG files."""

from __future__ import annotations

import argparse
from pathlib import Path


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``plot`` subcommand."""
    p = subparsers.add_parser("plot", help="write the figures of a result: a sweep or a continued branch (PNG)",
                              description="Draw the figures a result's study asks for (bifurcation "
                                          "diagram and P_d curves, periodicity map or case panels), or the "
                                          "forced response of a branch written by 'blademodel continue --out', "
                                          "and print the paths of the PNG files.")
    p.add_argument("result", metavar="RESULT.nc", help="result file of 'sweep', 'reproduce' or 'continue --out'")
    p.add_argument("--out", metavar="DIR", help="directory of the figures (default: next to the result)")
    p.add_argument("--state", default=None,
                   help="a branch's state drawn (default: its first coordinate), or a pattern such as 'x*' "
                        "(quoted): the largest and the smallest of the states it matches")
    p.add_argument("--quantity", choices=("harmonic", "amplitude", "section"), default=None,
                   help="what a branch's figure draws, as for 'continue --plot': first-harmonic amplitude (an FRF, "
                        "default), half the peak-to-peak excursion, or the Poincare samples (a bifurcation diagram); "
                        "written as <stem>_branch.png, <stem>_amplitude.png, <stem>_section.png. Its P_d is drawn "
                        "too, where the file allows")
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> int:
    """Write the figures and print their paths; return the exit code."""
    from ..orbits.branch_file import is_branch_file
    from ..plots import plot_result
    branch_only = [f"{option} {value!r}" for option, value in (("--state", args.state), ("--quantity", args.quantity))
                   if value is not None]
    if branch_only and not is_branch_file(args.result):
        raise ValueError(f"{', '.join(branch_only)}: only a branch file (from 'blademodel continue --out') is drawn "
                         f"so; {args.result} is a sweep's result")
    paths = plot_branch(Path(args.result), args.out, args.state, args.quantity or "harmonic") \
        if is_branch_file(args.result) else plot_result(args.result, args.out)
    for path in paths:
        print(path)
    return 0


def plot_branch(path: Path, out_dir=None, state: str | None = None, quantity: str = "harmonic") -> list[Path]:
    """The forced response (first harmonic of ``state``, a name or a pattern; default the first coordinate) of a
    branch file, ``<stem>_branch.png`` (or its ``quantity`` of :func:`~blademodel.plots.branch.branch_figure`,
    ``<stem>_<quantity>.png``), and its vibration reduction ``P_d``, ``<stem>_reduction.png`` (where the
    file keeps its orbits' mean squares and its config, and the model without contacts has a closed-form steady
    state). The branches ``blademodel continue --switch`` saved beside it (``<stem>_pd1.nc``, ...,
    ``<stem>_bp1.nc``, ...: :func:`switched_files`) are drawn with it, as ``continue --plot`` drew them."""
    import matplotlib.pyplot as plt

    from ..orbits.branch_file import branch_origin, load_branch
    from ..plots.branch import branch_figure
    _, config = branch_origin(path)
    branch = load_branch(path)
    folder = Path(out_dir) if out_dir else path.parent
    folder.mkdir(parents=True, exist_ok=True)
    from ..orbits.branch_states import state_indices
    state = state or branch.state_names[0]
    state_indices(branch.state_names, state, "--state")   # a bad name is named before anything is drawn
    switched = switched_files(path)
    drawn = [(branch, path)] + [(load_branch(f), f) for f, _ in switched]
    labels = [f"period {branch.periods}"] + [label for _, label in switched] if switched else None
    fig = branch_figure([b for b, _ in drawn], state, quantity=quantity, labels=labels)
    out = folder / f"{path.stem}_{'branch' if quantity == 'harmonic' else quantity}.png"
    fig.savefig(out, dpi=120)
    plt.close(fig)
    written = [out]
    reductions = [_branch_reduction(config, b, f) for b, f in drawn]
    if reductions[0] is not None:
        kept = [(b, r[1], label) for (b, _), r, label in zip(drawn, reductions, labels or [None] * len(drawn))
                if r is not None]
        fig = branch_figure([b for b, _, _ in kept], reductions[0][0], quantity="reduction",
                            values=[v for _, v, _ in kept], labels=[x for _, _, x in kept] if labels else None)
        written.append(folder / f"{path.stem}_reduction.png")
        fig.savefig(written[-1], dpi=120)
        plt.close(fig)
    return written


#: The file names ``blademodel continue --switch`` gives the branches it switched to beside ``--out FILE.nc``:
#: FILE_pd<k>.nc (born at the k-th period doubling) and FILE_bp<k>.nc (crossing at the k-th branch point).
SWITCHED = {"pd": ("doubling", "doubled at {k}"), "bp": ("branch_point", "crossing at branch point {k}")}


def switched_files(path: Path) -> list[tuple[Path, str]]:
    """The branch files ``blademodel continue --switch`` saved beside the branch file ``path``, each with its label
    in a figure (doubled ones first, each kind by its number): named after it (:data:`SWITCHED`), switched in the
    same run (their ``run`` settings are its own with the doubling or branch point named, their config its own);
    none for a switched branch's own file."""
    import glob
    import re

    from ..orbits.branch_file import branch_origin
    run, config = branch_origin(path)
    if run is None or any(key in run for key, _ in SWITCHED.values()):
        return []
    found = []
    for j, (tag, (key, label)) in enumerate(SWITCHED.items()):
        for f in path.parent.glob(f"{glob.escape(path.stem)}_{tag}*.nc"):
            m = re.fullmatch(rf"{re.escape(path.stem)}_{tag}([1-9][0-9]*)\.nc", f.name)
            their_run, their_config = branch_origin(f) if m else (None, None)
            if their_run is not None and their_config == config and their_run == {**run, key: int(m.group(1))}:
                found.append((j, int(m.group(1)), f, label.format(k=int(m.group(1)))))
    return [(f, label) for _, _, f, label in sorted(found)]


def _branch_reduction(data: dict | None, branch, path: Path) -> tuple | None:
    """``(what it sums, P_d at each point)`` of the branch of the file ``path`` that keeps its orbits' mean squares
    and its config (``data``), where the model without contacts has a closed-form steady state; else None."""
    import numpy as np

    from ..config.loading import config_from_data
    from ..orbits.branch_reduction import branch_vibration_reduction
    if data is None or not np.isfinite(branch.mean_squares).any():
        return None
    from ..sweep.point import observed
    config = config_from_data(data, source=str(path))
    try:
        values = branch_vibration_reduction(branch, config)
    except ValueError:
        return None
    return ", ".join(observed(config.build())), values
