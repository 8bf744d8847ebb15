"""Figures of sweep results: case panels, bifurcation diagrams, P_d curves, periodicity maps.

Every function returns a :class:`matplotlib.figure.Figure` built without
:mod:`matplotlib.pyplot`, so no window is ever opened and no backend needs to
be chosen; :func:`plot_result` writes the figures a study asks for as PNG
files.
"""

from __future__ import annotations

from pathlib import Path

from .bifurcation import bifurcation_figure
from .case import case_figure, cases_figure
from .common import FAILED, laws_of, motion_codes, study_of
from .periodicity_map import periodicity_map_figure
from .reduction import has_reduction, reduction_figure

__all__ = ["plot_result", "load_result", "case_figure", "cases_figure", "bifurcation_figure",
           "reduction_figure", "periodicity_map_figure"]

#: Resolution of the saved PNG files.
DPI = 150


def load_result(path):
    """Open a result file, with a clear :class:`ValueError` when it is missing or not a result.

    Parameters
    ----------
    path : path-like
        A NetCDF file written by :func:`blademodel.sweep.run_study`.

    Returns
    -------
    xarray.Dataset
        As :func:`blademodel.sweep.open_result` returns it.
    """
    from ..sweep import open_result
    path = Path(path)
    if not path.exists():
        raise ValueError(f"no such result file: {path}")
    if not path.is_file():
        raise ValueError(f"{path} is not a file")
    from ..sweep.errors import ResultFileError
    try:
        ds = open_result(path)
    except ResultFileError:   # empty, unreadable or damaged: its message says what to do
        raise
    except KeyError as e:
        raise ValueError(f"{path} is not a blademodel result file (no {e.args[0]!r} attribute)") from None
    except (OSError, ValueError, TypeError) as e:  # json.JSONDecodeError is a ValueError
        why = (str(e).splitlines() or [type(e).__name__])[0]
        if "did not find a match" in why:
            why = "not a NetCDF file"
        raise ValueError(f"{path} is not a readable blademodel result file ({why})") from None
    missing = [v for v in ("law", "motion", "poincare_x1", "poincare_vx1") if v not in ds]
    if missing:
        raise ValueError(f"{path} is not a blademodel result file (no {', '.join(missing)})")
    return ds


def _kind(ds) -> str:
    st = study_of(ds)
    plot = st.get("plot")
    if plot:
        return plot
    if st.get("cases"):
        return "cases"
    return "map" if len(ds.attrs.get("fields", [])) == 2 else "bifurcation"


def plot_result(path_or_ds, out_dir=None) -> list[Path]:
    """Write the figures of a result as PNG files, as its study's ``plot`` asks.

    ``bifurcation``: the bifurcation diagram, plus the ``P_d`` curves when the
    result has them; ``reduction``: the ``P_d`` curves; ``map``: the
    periodicity map (a bifurcation diagram if the sweep is not 2-D);
    ``cases``: the case panels, one figure per friction law.

    Parameters
    ----------
    path_or_ds : path-like or xarray.Dataset
        A result file or an opened result.
    out_dir : path-like, optional
        Directory of the PNG files (created if needed); default: next to the
        result file (the current directory for a dataset).

    Returns
    -------
    list of Path
        The files written, named ``<result stem>_<figure>.png``.

    Raises
    ------
    ValueError
        If the file is missing or not a result, or no point has run yet.
    """
    if isinstance(path_or_ds, (str, Path)):
        path = Path(path_or_ds)
        ds = load_result(path)
        stem, default_dir = path.stem, path.parent
    else:
        ds = path_or_ds
        stem, default_dir = study_of(ds).get("name") or "result", Path(".")
    out = Path(out_dir) if out_dir is not None else default_dir
    if not (motion_codes(ds) >= FAILED).any():
        raise ValueError("no point of this result has run yet")
    kind = _kind(ds)
    figures = []
    if kind == "cases":
        laws = laws_of(ds)
        if len(laws) == 1:
            figures.append(("cases", cases_figure(ds)))
        else:
            figures += [(f"cases_{law}", cases_figure(ds, law=law)) for law in laws]
    elif kind == "reduction":
        if not has_reduction(ds):
            raise ValueError("a reduction study without P_d in its result (run.vibration_reduction is off, "
                             "or no point finished)")
        figures.append(("reduction", reduction_figure(ds)))
    elif kind == "map" and len(ds.attrs.get("fields", [])) == 2:
        figures.append(("map", periodicity_map_figure(ds)))
    else:
        figures.append(("bifurcation", bifurcation_figure(ds)))
        if has_reduction(ds):
            figures.append(("reduction", reduction_figure(ds)))
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, fig in figures:
        target = out / f"{stem}_{name}.png"
        fig.savefig(target, dpi=DPI)
        written.append(target)
    return written
