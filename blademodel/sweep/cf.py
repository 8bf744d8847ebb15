"""CF metadata of result files: coordinates, long names, units, global attributes.

A result file follows the CF conventions (version 1.8) so that any NetCDF tool
reads it without blademodel: ``point``, ``sample`` and ``state`` are coordinate
variables (the point index, the recorded period, the state's name), the swept
fields and the law are auxiliary coordinates of every per-point variable
(``coordinates`` attribute), every variable has a ``long_name`` and, where it
has a physical dimension, ``units`` (UDUNITS spelling); character variables
carry ``_Encoding = "utf-8"``, so that xarray reads them as ``str``. ``history``
has no time stamp, so that every run of a study writes the same bytes.
"""

from __future__ import annotations

import re
from typing import Optional

from .. import __version__

CONVENTIONS = "CF-1.8"

#: ``long_name`` and ``units`` (None: dimensionless or mixed) of every stored variable.
VARIABLES = {
    "point": ("index of the point in the study", None),
    "sample": ("index of the recorded excitation period after the transient", None),
    "state": ("name of the state: coordinates, their velocities (v...), then friction-law states", None),
    "law": ("friction law of the point", None),
    "done": ("1 when the point is finished and sealed, 0 while pending", None),
    "checksum": ("BLAKE2b checksum of the point's stored row", None),
    "error": ("error of a failed point (empty when it succeeded)", None),
    "length_scale": ("length scale of the non-dimensional state (the gap)", "m"),
    "period": ("period n of the Poincare samples (0: none up to 16)", None),
    "motion": ("motion class: n > 0 period-n, 0 nonperiodic, -1 quasi-periodic, -2 chaos", None),
    "lyapunov": ("largest Lyapunov exponent per excitation period", None),
    "P": ("mean square of x1 and y1 over the recorded periods (summed)", "m2"),
    "P0": ("mean square of x1 and y1 without contacts (summed)", "m2"),
    "Pd": ("vibration reduction (P0 - P) / P0", "percent"),
    "events": ("events (impacts, separations, stick-slip transitions) over the recorded periods", None),
    "max_cone_ratio": ("largest friction force of a sticking Coulomb contact over mu N", None),
    "poincare_x1": ("x1 at the end of each recorded excitation period (Poincare section)", "m"),
    "poincare_vx1": ("dx1/dt at the end of each recorded excitation period (Poincare section)", "m s-1"),
    "final_state": ("state at the end of the run (m for coordinates, m s-1 for velocities)", None),
    "harmonic1": ("first-harmonic amplitude of each coordinate and velocity over the recorded periods "
                  "(m for coordinates, m s-1 for velocities)", None),
    "history_t": ("time of the kept time history", "s"),
    "history_x1": ("x1 over the kept time history", "m"),
    "history_vx1": ("dx1/dt over the kept time history", "m s-1"),
}

#: Units as the configs' field descriptions write them (``"mass, kg"``), in UDUNITS spelling.
_UNITS = {"kg": "kg", "m": "m", "N": "N", "rad": "rad", "s": "s", "N/m": "N m-1", "N s/m": "N s m-1",
          "rad/s": "rad s-1", "m/s": "m s-1", "Hz": "Hz"}


def field_metadata(config, field: str) -> tuple[str, Optional[str]]:
    """``(long_name, units)`` of a swept config field, from the config class's field description.

    A description ends with its unit after a comma (``"excitation frequency, rad/s"``); a
    field without one is dimensionless (units None). Nested fields (``contacts.1.gap``) are
    looked up in the nested model.
    """
    target, name = config, field
    for part in field.split(".")[:-1]:
        target = target[int(part)] if part.isdigit() else getattr(target, part, None)
        if target is None:
            return f"swept field {field}", None
    name = field.split(".")[-1]
    info = getattr(type(target), "model_fields", {}).get(name)
    description = (info.description or "") if info is not None else ""
    if not description:
        return f"swept field {field}", None
    text = re.sub(r"\s*\(.*\)$", "", description)   # "..., m (< 0: preload)" -> "..., m"
    head, _, tail = text.rpartition(", ")
    if head and tail in _UNITS:
        return f"{head} ({field})", _UNITS[tail]
    return f"{description} ({field})", None


def annotate(ds, *, fields: list[str], field_meta: dict, title: str, config_json: Optional[str],
             observe: Optional[list[str]] = None) -> None:
    """Put the CF attributes on a result file being created (a :class:`netCDF4.Dataset` in define mode).

    ``observe``: the observed coordinates; the ``x1``-named variables hold the first
    of them and their long names say which.
    """
    auxiliary = " ".join([f"param_{f}" for f in fields] + ["law"])
    observe = list(observe or ["x1", "y1"])
    for name, var in ds.variables.items():
        long_name, units = VARIABLES.get(name, (None, None))
        if long_name and (name.endswith("x1") or name in ("P", "P0")):
            long_name = long_name.replace("x1 and y1", " and ".join(observe)).replace("x1", observe[0])
        if name.startswith("param_"):
            long_name, units = field_meta.get(name[len("param_"):], (f"swept field {name[6:]}", None))
        if long_name:
            var.long_name = long_name
        if units:
            var.units = units
        if var.dtype == "S1" or str(var.dtype) == "|S1":
            var._Encoding = "utf-8"
        if "point" in var.dimensions and name not in ("point", "law") and not name.startswith("param_"):
            var.coordinates = auxiliary
    ds.Conventions = CONVENTIONS
    ds.title = title or "blademodel result"
    ds.source = f"blademodel {__version__}"
    # No time stamp: serial, process, Dask and resumed runs of a study write bit-identical files.
    ds.history = f"created by blademodel {__version__} (blademodel sweep / reproduce)"
    ds.comment = ("One row per point of the study in the attribute 'study'; a point is valid where done = 1 "
                  "(blademodel.open_result verifies the checksums).")
    if config_json is not None:
        ds.setncattr("config", config_json)
    ds.setncattr("observed", " ".join(observe))
