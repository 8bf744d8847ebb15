"""JSON output that stays valid JSON: non-finite numbers become ``null`` with a reason.

Python's :func:`json.dumps` writes ``NaN`` and ``Infinity``, which JSON does not
have; a reader such as ``jq`` or JavaScript's ``JSON.parse`` rejects the whole
object. :func:`finite_json` replaces each non-finite number by ``null`` and lists
it, by its dotted path, in an ``"undefined"`` object with the reason.
"""

from __future__ import annotations

import json
import math
from typing import Any, Mapping

import numpy as np


def _clean(obj: Any, path: str, undefined: dict) -> Any:
    if isinstance(obj, Mapping):
        return {k: _clean(v, f"{path}.{k}" if path else str(k), undefined) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, np.ndarray)):
        return [_clean(v, f"{path}.{i}", undefined) for i, v in enumerate(obj)]
    if isinstance(obj, (float, np.floating)) and not math.isfinite(obj):
        undefined.setdefault(path, f"not a finite number ({float(obj)})")
        return None
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def finite_json(report: Mapping[str, Any], reasons: Mapping[str, str] | None = None) -> dict:
    """A copy of ``report`` with ``null`` for every NaN or infinity, and the reasons listed.

    Parameters
    ----------
    report : mapping
        Nested dicts, lists, numbers and strings (NumPy scalars and arrays too).
    reasons : mapping of str to str, optional
        Why a value is undefined, by dotted path (``{"Pd": "P0 = 0.0: ..."}``);
        these are listed whether the value is ``None`` or not finite.

    Returns
    -------
    dict
        ``report`` with non-finite numbers replaced by ``None`` and, if any value
        is undefined, an ``"undefined"`` entry mapping each path to its reason.
    """
    undefined = dict(reasons or {})
    out = _clean({k: v for k, v in report.items() if k != "undefined"}, "", undefined)
    if undefined:
        out["undefined"] = undefined
    return out


def dumps(report: Mapping[str, Any], reasons: Mapping[str, str] | None = None, **kwargs) -> str:
    """:func:`finite_json` of ``report`` as text; never writes ``NaN`` or ``Infinity``."""
    return json.dumps(finite_json(report, reasons), allow_nan=False, **kwargs)
