"""Run a study into a result file: grid, executor, incremental storage, resume."""

from __future__ import annotations

import itertools
import json
import sys
from pathlib import Path
from typing import Callable

import numpy as np

from . import storage
from .. import interrupts
from .errors import ResultFileError, SweepInterrupted
from .executors import choose
from .lock import ResultLock
from ..analysis import motion_class
from ..progress import Progress
from .cf import field_metadata
from .point import build_config, motion_code, observed, run_point
from .spec import Study


def points(study: Study) -> tuple[list[str], list[list[float]], list[str], list[dict]]:
    """The study's points: field names, their values per point, laws, and overrides.

    Laws vary slowest, then the first swept field, then the second (row-major),
    so a 2-D map reshapes to ``(law, field1, field2)``.
    """
    laws = study.laws or [study.base.get("friction", "coulomb")]
    if study.cases:
        fields = sorted({k for c in study.cases for k in c})
        combos = [[float(c.get(f, np.nan)) for f in fields] for c in study.cases]
    else:
        fields = list(study.sweep)
        combos = [list(v) for v in itertools.product(*(study.sweep[f].grid() for f in fields))]
    values, law_of, overrides = [], [], []
    for law in laws:
        for combo in combos:
            over = {f: v for f, v in zip(fields, combo) if not np.isnan(v)}
            if study.laws:
                over["friction"] = law
                if law in (study.law_options or {}):
                    over["friction_options"] = study.law_options[law]
                elif study.base.get("friction_options") and law != study.base.get("friction", "coulomb"):
                    over["friction_options"] = {}   # the base's options belong to the base's law
            values.append(combo)
            law_of.append(law)
            overrides.append(over)
    return fields, values, law_of, overrides


def _state_names(model) -> list[str]:
    """The names of the state vector, as the kernels name it: coordinates, ``v`` + coordinates, law states."""
    coords = list(model.coordinates)
    return [*coords, *(f"v{c}" for c in coords), *(label for label, _, _ in model.law_state_labels())]


def _say(message: str) -> None:
    print(message, file=sys.stderr)


def _prepare(out: Path, layout: dict, expected: tuple, study_json: str, restart: bool,
             log: Callable[[str], None] | None) -> list[int]:
    """Create, verify (and repair) the result file; return the points still to run."""
    storage.remove_aside(out)
    if out.exists() and restart:
        out.unlink()
    if not out.exists():
        storage.create(out, **layout)
        return list(range(len(expected[1])))
    found = storage.check(out, study_json, expected)
    if not found.checksums and log:
        log(f"{out}: written by an older blademodel without checksums, so its points cannot be verified; "
            f"--restart recomputes them")
    if not found.intact:
        if log:
            log(f"{out} is damaged: {found.describe()}; keeping the {len(found.done)} point(s) that verify "
                f"and running the others again")
        storage.rebuild(out, found.done, **layout)
    done = set(found.done)
    todo = [i for i in range(found.n_points) if i not in done]
    if log and done:
        if todo:
            log(f"{out}: resuming: {len(done)} of {found.n_points} points already done, running the other "
                f"{len(todo)} (--restart starts over)")
        else:
            log(f"{out}: all {found.n_points} points are already done; using them (--restart recomputes them)")
    return todo


def run_study(study: Study, out: str | Path, *, workers: int | None = None, scheduler: str | None = None,
              restart: bool = False, progress: Callable[[int, int], None] | str | None = "stderr",
              log: Callable[[str], None] | None = _say) -> Path:
    """Run every pending point of ``study`` into the NetCDF file ``out``.

    The file is locked for the run (:class:`~blademodel.sweep.lock.ResultLock`);
    an existing file is verified first (:func:`~blademodel.sweep.storage.check`):
    a damaged one is rebuilt from its points that verify and the others are run
    again.

    Parameters
    ----------
    study : Study
    out : path
        Result file; if it exists and holds the same study, only the points not
        yet done are run (resume).
    workers : int, optional
        Processes (default all cores; 1 runs in this process).
    scheduler : str, optional
        Address of a Dask distributed scheduler to run the points on.
    restart : bool
        Discard an existing file and start again.
    progress : callable, "stderr" or None
        ``progress(done, total)`` after every point. ``"stderr"`` (default): a
        :class:`~blademodel.progress.Progress` on standard error (a bar on a
        terminal, a line every 30 s otherwise); None: silent.
    log : callable, optional
        ``log(message)`` for what the run finds in an existing file (resumed,
        reused, repaired); default: printed to stderr.

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    ResultFileError
        If ``out`` is empty, unreadable or holds another study (``restart`` discards it).
    ResultLockedError
        If another process is writing ``out``.
    WorkerLostError, SchedulerError
        If a pool worker dies, or the Dask scheduler cannot be reached.
    SweepInterrupted
        On Ctrl-C (a :class:`KeyboardInterrupt`); the message says how to resume.
    """
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    study_json = study.model_dump_json()
    fields, values, laws, overrides = points(study)
    run = study.run.model_dump()
    # Validate the base config once, here, so a bad study fails before any work.
    n_state, state_names, base_config = 0, [], None
    for law in sorted(set(laws)):
        config = build_config(study.base, overrides[laws.index(law)])
        model = config.build()
        observe = observed(model, run["observe"])
        names = _state_names(model)
        if len(names) > n_state:
            n_state, state_names = len(names), names
        if base_config is None:
            base_config = build_config(study.base, {})
    field_meta = {f: field_metadata(base_config, f) for f in fields}
    layout = dict(study_json=study_json, fields=fields, values=values, laws=laws, periods=run["periods"],
                  n_state=n_state, state_names=state_names, field_meta=field_meta, observe=list(observe),
                  config_json=base_config.model_dump_json(),
                  history=run["history_periods"] * run["steps_per_period"] + 1 if run["history_periods"] else 0)
    total = len(values)
    if progress == "stderr":
        progress = Progress("points", label=out.name)
    with ResultLock(out):
        todo = _prepare(out, layout, (fields, values, laws), study_json, restart, log)
        done = total - len(todo)
        if progress:
            progress(done, total)

        def keep(i, result):
            """Write point ``i`` (a signal meanwhile is raised once it is saved), count it, and act on a signal whose
            exception compiled code swallowed."""
            nonlocal done
            with interrupts.deferred():
                storage.write_point(out, i, result)
            done += 1
            if progress:
                progress(done, total)
            interrupts.check()

        try:
            if run["warm_start"]:
                # Each point starts where the previous one (same law) ended: a chain, so serial.
                for i in todo:
                    prev = storage.final_state(out, i - 1) if i > 0 and laws[i - 1] == laws[i] else None
                    keep(i, run_point(study.base, overrides[i], run, y0=prev))
                return out
            tasks = [(i, study.base, overrides[i], run) for i in todo]
            results = choose(workers, scheduler)(tasks)
            try:
                for i, result in results:
                    keep(i, result)
            finally:   # stops the executor's workers now if this loop ended early
                close = getattr(results, "close", None)
                if close is not None:
                    close()
        except KeyboardInterrupt:
            interrupts.acknowledge()
            interrupt = getattr(progress, "interrupt", None)
            if interrupt is not None:
                interrupt()   # end a half-drawn progress bar's line
            try:   # the file is the truth: the Ctrl-C can land after a point is written, before it is counted
                done = total - len(storage.pending(out, study_json))
            except Exception:   # unreadable now: this run's own count
                pass
            raise SweepInterrupted(f"interrupted: {done} of {total} points are saved in {out}; run the same "
                                   f"command again to resume") from None
    return out


def open_result(path: str | Path):
    """The result file as an :class:`xarray.Dataset`, with the study in ``attrs``.

    The file is verified first (:func:`~blademodel.sweep.storage.check`), so a
    damaged file never passes its zeros off as data. The file itself follows the
    CF conventions (:mod:`blademodel.sweep.cf`) and opens with plain
    :func:`xarray.open_dataset` too; ``open_result`` adds the check, parses the
    JSON attributes and re-derives the motion class with the current rule.

    Parameters
    ----------
    path : path
        A result file of ``blademodel sweep`` or ``blademodel reproduce``.

    Returns
    -------
    xarray.Dataset
        Dimensions ``point`` (one per point of the study), ``sample``
        (recorded periods), ``state`` (coordinates, velocities, law states) and
        ``time`` (kept history). Coordinates: ``point``, ``sample``, ``state``
        (names), the swept fields ``param_<field>`` and ``law`` along ``point``.
        Per point: ``done``, ``error`` (``""`` when it succeeded), ``period``,
        ``motion`` (``n > 0`` period-n, 0 nonperiodic, -1 quasi-periodic, -2
        chaos), ``lyapunov``, ``P``, ``P0``, ``Pd``, ``events``,
        ``max_cone_ratio``, ``length_scale``; per point and sample
        ``poincare_x1``, ``poincare_vx1``; per point and state ``final_state``,
        ``harmonic1``. ``attrs``: ``study`` and ``config`` (dicts), ``fields``
        (list), ``Conventions``, ``title``, ``history``.

    Examples
    --------
    >>> ds = open_result("out/fig17/fig17.nc")                     # doctest: +SKIP
    >>> coulomb = ds.where(ds.law == "coulomb", drop=True)         # doctest: +SKIP
    >>> coulomb.Pd.plot(x="param_gamma")                           # doctest: +SKIP

    Raises
    ------
    ResultFileError
        If the file is empty, unreadable, cut short or a done point fails its checksum.
    """
    import xarray as xr
    found = storage.check(path)
    if not found.intact:
        raise ResultFileError(f"{path} is damaged: {found.describe()}; run its sweep again to recompute "
                              f"the damaged points")
    ds = xr.load_dataset(path)
    for name in ("law", "error"):  # character arrays in the classic format: back to str
        if ds[name].dtype.kind == "S":
            ds[name] = ds[name].astype(str)
    ds.attrs["study"] = json.loads(ds.attrs["study"])
    ds.attrs["fields"] = json.loads(ds.attrs["fields"])
    if "config" in ds.attrs:   # files written before it existed have none
        ds.attrs["config"] = json.loads(ds.attrs["config"])
    # The class is derived from the stored raw data (period, exponent) with the
    # current rule, so an older file never shows a stale classification.
    motion = ds["motion"].values.astype(float)
    for i, (period, lam, err) in enumerate(zip(ds["period"].values, ds["lyapunov"].values, ds["error"].values)):
        if ds["done"].values[i] and not err and not np.isnan(period):
            motion[i] = motion_code(motion_class(int(period), None if np.isnan(lam) else float(lam)))
    ds["motion"] = ("point", motion)
    return ds
