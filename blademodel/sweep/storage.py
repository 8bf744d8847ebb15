"""Incremental NetCDF storage of a sweep, one point at a time, with resume and integrity checks.

The file is laid out in full when the sweep starts, in the NetCDF classic
(64-bit offset) format: every output filled with NaN, ``done = 0``. After that
the header never changes; a finished point's values are written in place (the
whole row of every variable) and synced to disk *before* its checksum and its
``done`` flag are set, by the single writer process (see
:mod:`blademodel.sweep.lock`). So a sweep killed at any instant leaves a
readable file in which every point marked done is complete; the others are run
again on resume.

Damage from outside (a copy cut short, a full disk, flipped bytes) is found by
:func:`check`: every done point carries a checksum of its row (parameters, law,
outputs, error), and the last variable of the file, ``tail``, holds a magic
number that reads as 0 when the file is cut anywhere before its end. A damaged
file is rebuilt (:func:`rebuild`) from the points that verify; the rest are
computed again, so zeros of a cut file are never taken for data.

The study, the base config and the run settings travel in the file's
attributes, so a result file says how it was made.
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import netCDF4
import numpy as np

from .. import __version__
from .cf import annotate
from .errors import ResultFileError

#: Per-point scalars. ``max_cone_ratio``: the largest ``|f| / (mu N)`` of a sticking
#: Coulomb contact (per-contact kernel; NaN for the product kernel).
SCALARS = ("length_scale", "period", "motion", "lyapunov", "P", "P0", "Pd", "events", "max_cone_ratio")
INTS = ("period", "motion", "events")
#: Per-point arrays (a row per point).
ARRAYS = ("poincare_x1", "poincare_vx1", "final_state", "harmonic1", "history_t", "history_x1", "history_vx1")
LAW_CHARS, ERROR_CHARS, CHECKSUM_CHARS = 32, 400, 16
FORMAT = "NETCDF3_64BIT_OFFSET"
#: Value of the last variable, ``tail``: a file cut short reads 0 there.
TAIL_MAGIC = 0x626C6D64
INT_FILL = -999
#: Variables every result file has.
REQUIRED = ("point", "done", "law", "error", "poincare_x1", "poincare_vx1")


def _chars(text: str, n: int) -> np.ndarray:
    return netCDF4.stringtoarr(text.encode("utf-8", "replace")[:n].decode("utf-8", "ignore"), n)


def study_signature(study_json: str) -> str:
    """What must match for a file to be resumed: the study without presentation fields."""
    d = json.loads(study_json)
    for k in ("title", "paper", "plot", "claims"):
        d.pop(k, None)
    if not d.get("law_options"):
        d.pop("law_options", None)   # files written before law_options existed still resume
    if d.get("run", {}).get("observe") is None:
        d.get("run", {}).pop("observe", None)   # likewise run.observe
    return json.dumps(d, sort_keys=True)


def _fsync(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def create(path: Path, *, study_json: str, fields: list[str], values: list[list], laws: list[str],
           periods: int, n_state: int, history: int, state_names: list[str] | None = None,
           field_meta: dict | None = None, config_json: str | None = None,
           observe: list[str] | None = None) -> None:
    """Lay out a new result file for ``len(values)`` points (written aside, then renamed into place).

    ``state_names`` name the ``state`` coordinate, ``field_meta`` gives each swept
    field's ``(long_name, units)``, ``config_json`` is the full validated base
    config (attribute ``config``) and ``observe`` the observed coordinates (attribute
    ``observed``, :func:`~blademodel.sweep.point.observed`); see :mod:`blademodel.sweep.cf`.
    """
    path = Path(path)
    tmp = path.with_name(path.name + ".new")
    with netCDF4.Dataset(tmp, "w", format=FORMAT) as ds:
        n = len(values)
        ds.createDimension("point", n)
        ds.createDimension("law_chars", LAW_CHARS)
        ds.createDimension("error_chars", ERROR_CHARS)
        ds.createDimension("checksum_chars", CHECKSUM_CHARS)
        ds.createDimension("sample", periods)
        ds.createDimension("state", n_state)
        if history:
            ds.createDimension("time", history)
        ds.setncattr("study", study_json)
        ds.setncattr("signature", study_signature(study_json))
        ds.setncattr("fields", json.dumps(fields))
        ds.setncattr("blademodel_version", __version__)
        ds.createVariable("point", "i4", ("point",))[:] = np.arange(n)
        ds.createVariable("sample", "i4", ("sample",))[:] = np.arange(periods)
        names = list(state_names or [])[:n_state]
        names += [f"state{k}" for k in range(len(names), n_state)]
        ds.createDimension("name_chars", max([len(x.encode()) for x in names] + [1]))
        sv = ds.createVariable("state", "S1", ("state", "name_chars"))
        sv.set_auto_chartostring(False)
        for k, name in enumerate(names):
            sv[k, :] = _chars(name, len(ds.dimensions["name_chars"]))
        for j, f in enumerate(fields):
            v = ds.createVariable(f"param_{f}", "f8", ("point",))
            v[:] = [row[j] for row in values]
        lv = ds.createVariable("law", "S1", ("point", "law_chars"))
        lv.set_auto_chartostring(False)
        for i, law in enumerate(laws):
            lv[i, :] = _chars(law, LAW_CHARS)
        ds.createVariable("done", "i1", ("point",))[:] = 0
        # Near the start: a file cut short keeps the checksums of the points whose rows survive.
        cv = ds.createVariable("checksum", "S1", ("point", "checksum_chars"))
        cv.set_auto_chartostring(False)
        cv[:] = np.zeros((n, CHECKSUM_CHARS), dtype="S1")
        for name in SCALARS:
            kind = "i4" if name in INTS else "f8"
            var = ds.createVariable(name, kind, ("point",), fill_value=INT_FILL if kind == "i4" else np.nan)
            var[:] = INT_FILL if kind == "i4" else np.nan
        for name in ("poincare_x1", "poincare_vx1"):
            ds.createVariable(name, "f8", ("point", "sample"), fill_value=np.nan)
        ds.createVariable("final_state", "f8", ("point", "state"), fill_value=np.nan)
        ds.createVariable("harmonic1", "f8", ("point", "state"), fill_value=np.nan)
        if history:
            for name in ("history_t", "history_x1", "history_vx1"):
                ds.createVariable(name, "f8", ("point", "time"), fill_value=np.nan)
        ev = ds.createVariable("error", "S1", ("point", "error_chars"))
        ev.set_auto_chartostring(False)
        ev[:] = np.zeros((n, ERROR_CHARS), dtype="S1")
        ds.createVariable("tail", "i4", ()).assignValue(TAIL_MAGIC)   # last: at the end of the file
        ds["tail"].long_name = "end marker: reads 0 in a file cut short"
        annotate(ds, fields=fields, field_meta=field_meta or {}, title=json.loads(study_json).get("title", ""),
                 config_json=config_json, observe=observe)
    _fsync(tmp)
    tmp.replace(path)


#: Files written aside next to a result file (``x.nc.new``, ``x.nc.rebuild``, ...) before being renamed.
ASIDE = (".new", ".rebuild", ".rebuild.new")


def remove_aside(path: Path) -> None:
    """Remove what a killed :func:`create` or :func:`rebuild` left next to ``path`` (hold the lock)."""
    path = Path(path)
    for suffix in ASIDE:
        path.with_name(path.name + suffix).unlink(missing_ok=True)


def _row_variables(ds) -> list[str]:
    """The variables a point's checksum covers, in a fixed order."""
    fields = json.loads(ds.getncattr("fields"))
    names = [f"param_{f}" for f in fields] + ["law"]
    names += [n for n in SCALARS + ARRAYS if n in ds.variables] + ["error"]
    return names


def _digest(index: int, rows: list[np.ndarray]) -> bytes:
    h = hashlib.blake2b(np.int64(index).astype("<i8").tobytes(), digest_size=CHECKSUM_CHARS // 2)
    for row in rows:
        row = np.asarray(row)
        if row.dtype.kind in "fiu":
            row = row.astype(row.dtype.newbyteorder("<"), copy=False)
        h.update(np.ascontiguousarray(row).tobytes())
    return h.hexdigest().encode()


def _raw(ds) -> None:
    """Read and write the stored values themselves (no masks, no character conversion)."""
    ds.set_auto_maskandscale(False)
    ds.set_auto_chartostring(False)


def write_point(path: Path, index: int, out: dict) -> None:
    """Write one finished (or failed) point and mark it done.

    Every variable's whole row is written (NaN or the fill value where ``out``
    has nothing), then synced, then the row's checksum and the ``done`` flag.
    """
    with netCDF4.Dataset(path, "a") as ds:
        ds["error"].set_auto_chartostring(False)
        failed = "error" in out
        for name in SCALARS:
            if name in ds.variables:   # files written before a variable existed resume
                value = None if failed else out.get(name)
                ds[name][index] = (INT_FILL if name in INTS else np.nan) if value is None else value
        for name in ARRAYS:
            if name in ds.variables:
                row = np.full(ds[name].shape[1], np.nan)
                if not failed and name in out:
                    row[: len(out[name])] = out[name]
                ds[name][index, :] = row
        ds["error"][index, :] = _chars(out["error"] or "failed", ERROR_CHARS) if failed \
            else np.zeros(ERROR_CHARS, dtype="S1")
        ds.sync()  # the values reach the disk before the point is marked done
        _seal(ds, index)
        ds["done"][index] = 1


def _seal(ds, index: int) -> None:
    """Store the checksum of point ``index``'s row as it is in the file (files without checksums: nothing)."""
    if "checksum" in ds.variables:
        _raw(ds)
        rows = [ds[name][index] for name in _row_variables(ds)]
        ds["checksum"][index, :] = np.frombuffer(_digest(index, rows), dtype="S1")


@dataclass
class FileCheck:
    """What :func:`check` found in a result file.

    Attributes
    ----------
    n_points : int
    done : list of int
        Points marked done whose checksum verifies.
    damaged : list of int
        Points marked done whose checksum does not verify (or whose flag is not 0 or 1).
    truncated : bool
        The file ends before its last variable (``tail`` does not hold its magic number).
    layout_damaged : bool
        Parameters or laws differ from the ones expected.
    checksums : bool
        False for files written before checksums existed (nothing could be verified).
    """

    n_points: int
    done: list[int] = field(default_factory=list)
    damaged: list[int] = field(default_factory=list)
    truncated: bool = False
    layout_damaged: bool = False
    checksums: bool = True

    @property
    def intact(self) -> bool:
        """Nothing damaged: no bad point, not cut short, the layout as expected."""
        return not (self.damaged or self.truncated or self.layout_damaged)

    def describe(self) -> str:
        """One line on the damage found (empty when intact)."""
        parts = []
        if self.truncated:
            parts.append("the file is cut short")
        if self.layout_damaged:
            parts.append("its parameter or law table is damaged")
        if self.damaged:
            parts.append(f"{len(self.damaged)} done point(s) fail their checksum ({_ranges(self.damaged)})")
        return "; ".join(parts)


def _ranges(indices: list[int], limit: int = 12) -> str:
    shown = ", ".join(str(i) for i in indices[:limit])
    return shown + (f", ... ({len(indices)} in all)" if len(indices) > limit else "")


def open_dataset(path: Path) -> netCDF4.Dataset:
    """Open a result file for reading, or raise :class:`ResultFileError` saying why it cannot be read."""
    path = Path(path)
    if path.is_dir():
        raise ResultFileError(f"{path} is a directory, not a result file")
    size = path.stat().st_size
    if size == 0:
        raise ResultFileError(f"{path} is empty (0 bytes), not a result file; "
                              f"run the sweep with --restart to discard it and start again")
    try:
        ds = netCDF4.Dataset(path, "r")
    except (OSError, RuntimeError) as e:
        why = getattr(e, "strerror", None) or str(e) or type(e).__name__
        raise ResultFileError(f"{path} is not a readable result file ({why}); run the sweep with --restart "
                              f"to discard it and start again") from None
    missing = [n for n in REQUIRED if n not in ds.variables and n not in ds.dimensions]
    try:
        fields_ok = isinstance(json.loads(ds.getncattr("fields")), list) and "signature" in ds.ncattrs()
    except (AttributeError, ValueError):   # no such attribute, or not JSON
        fields_ok = False
    if missing or not fields_ok:
        ds.close()
        what = ", ".join(missing) if missing else "study attributes"
        raise ResultFileError(f"{path} is damaged or not a blademodel result file (no {what}); run the sweep "
                              f"with --restart to discard it and start again")
    return ds


def check(path: Path, study_json: str | None = None, expected: tuple | None = None) -> FileCheck:
    """Verify a result file: its study, its end, its layout and every done point's checksum.

    Parameters
    ----------
    path : path
        The result file.
    study_json : str, optional
        The study to resume; a file of another study is refused.
    expected : tuple, optional
        ``(fields, values, laws)`` the file must hold (its parameter and law table).

    Returns
    -------
    FileCheck

    Raises
    ------
    ResultFileError
        If the file is empty, unreadable, not a result file or (with ``study_json``) another study's.
    """
    path = Path(path)
    with open_dataset(path) as ds:
        if study_json is not None and ds.getncattr("signature") != study_signature(study_json):
            raise ResultFileError(f"{path} holds a different study or settings; remove it or pass --restart")
        _raw(ds)
        n = len(ds.dimensions["point"])
        flags = np.asarray(ds["done"][:])
        result = FileCheck(n_points=n, checksums="checksum" in ds.variables)
        if "tail" in ds.variables:
            result.truncated = int(ds["tail"].getValue()) != TAIL_MAGIC
        if expected is not None:
            fields, values, laws = expected
            stored_fields = json.loads(ds.getncattr("fields"))
            vals = np.asarray(values, dtype=float).reshape(len(values), len(fields))
            same = stored_fields == list(fields) and n == len(values) and all(
                np.array_equal(np.asarray(ds[f"param_{f}"][:], dtype=float), vals[:, j], equal_nan=True)
                for j, f in enumerate(fields))
            same = same and np.array_equal(np.asarray(ds["law"][:]),
                                           np.array([_chars(law, LAW_CHARS) for law in laws]).reshape(n, -1))
            result.layout_damaged = not same
        marked = [int(i) for i in np.flatnonzero(flags != 0)]
        if not result.checksums:
            result.done = marked
            return result
        names = _row_variables(ds)
        data = {name: np.asarray(ds[name][:]) for name in names}
        sums = np.asarray(ds["checksum"][:])
        for i in marked:
            ok = flags[i] == 1 and sums[i].tobytes() == _digest(i, [data[name][i] for name in names])
            (result.done if ok else result.damaged).append(i)
    return result


def rebuild(path: Path, keep: list[int], **layout) -> None:
    """Replace ``path`` by a fresh layout (``layout``: :func:`create`'s arguments) holding the points ``keep``.

    The kept rows are copied as stored, with their checksums, so the rebuilt file
    equals one that was never damaged. The new file is written aside and renamed
    into place: a kill during the rebuild leaves the old file.
    """
    path = Path(path)
    fresh = path.with_name(path.name + ".rebuild")
    create(fresh, **layout)
    with netCDF4.Dataset(path, "r") as src, netCDF4.Dataset(fresh, "a") as dst:
        _raw(src)
        _raw(dst)
        names = [n for n in SCALARS + ARRAYS + ("error", "checksum") if n in src.variables and n in dst.variables]
        for name in names:
            rows = np.asarray(src[name][:])
            for i in keep:
                dst[name][i] = rows[i]
        if "checksum" not in src.variables:   # a file from before checksums: seal its points now
            for i in keep:
                _seal(dst, i)
        dst.sync()
        for i in keep:
            dst["done"][i] = 1
    _fsync(fresh)
    fresh.replace(path)


def pending(path: Path, study_json: str) -> list[int]:
    """Indices of the points of ``path`` not yet done (or damaged); checks the file is this study's."""
    result = check(path, study_json)
    done = set(result.done)
    return [i for i in range(result.n_points) if i not in done]


def failures(path: Path) -> dict[int, str]:
    """``{index: error}`` of the done points that failed."""
    with open_dataset(path) as ds:
        _raw(ds)
        flags = np.asarray(ds["done"][:])
        errors = np.asarray(ds["error"][:])
    out = {}
    for i in np.flatnonzero(flags != 0):
        text = errors[i].tobytes().rstrip(b"\0").decode("utf-8", "replace")
        if text:
            out[int(i)] = text
    return out


def final_state(path: Path, index: int) -> np.ndarray | None:
    """Final state of a finished point (for a warm start), or ``None``.

    States of laws with fewer internal states are padded with NaN in the file.
    """
    with netCDF4.Dataset(path, "r") as ds:
        if not ds["done"][index]:
            return None
        v = np.asarray(ds["final_state"][index, :].filled(np.nan), dtype=float)
    v = v[~np.isnan(v)]
    return v if v.size else None
