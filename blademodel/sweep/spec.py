"""A study: a base model, the swept fields, run settings and what to plot."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Literal, Optional

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from ..components.friction import registry


#: What a study name may be: it names the result file and the figures.
NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,99}")


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class Axis(_Strict):
    """Values of one swept field: ``values``, or ``start``/``stop``/``num`` (``log`` spacing)."""

    start: Optional[float] = None
    stop: Optional[float] = None
    num: Optional[int] = Field(None, ge=1)
    log: bool = False
    values: Optional[list[float]] = None

    @model_validator(mode="after")
    def _check(self):
        if self.values is None and None in (self.start, self.stop, self.num):
            raise ValueError("give either values or start, stop and num")
        if self.log and self.values is None and (self.start <= 0 or self.stop <= 0):
            raise ValueError(f"log spacing needs positive start and stop, got {self.start}, {self.stop}")
        return self

    def grid(self, num: int | None = None) -> np.ndarray:
        """The values, or ``num`` of them when given (a coarse version)."""
        if self.values is not None:
            v = np.asarray(self.values, dtype=float)
            if num is not None and num < len(v):
                v = v[np.unique(np.linspace(0, len(v) - 1, num).round().astype(int))]
            return v
        n = self.num if num is None else min(num, self.num)
        return np.geomspace(self.start, self.stop, n) if self.log else np.linspace(self.start, self.stop, n)


class RunSettings(_Strict):
    """How each point is integrated and analysed."""

    transient: int = Field(300, ge=0, description="periods discarded")
    periods: int = Field(100, ge=2, description="periods recorded (Poincare samples)")
    steps_per_period: int = Field(1000, ge=10)
    event_tol: float = Field(1e-10, gt=0)
    lyapunov_periods: int = Field(0, ge=0, description="periods for the largest Lyapunov exponent (0: skip)")
    vibration_reduction: bool = Field(False, description="compute P_d against the contact-free system")
    warm_start: bool = Field(False, description="start each point from the previous point's final state")
    history_periods: int = Field(0, ge=0, description="last periods kept as a time history (case figures)")
    observe: Optional[list[str]] = Field(None, min_length=1,
                                         description="coordinates a point observes: P and P_d over all of them, "
                                                     "Poincare samples and history of the first (default: the "
                                                     "first mass's coordinates)")


class Claim(_Strict):
    """What a source (a paper) reports at one point of a study, to be set beside what is measured there.

    Attributes
    ----------
    at : dict of str to float
        The point: a value of every swept field, or the fields of one of the
        study's ``cases``. In a sweep the nearest grid point is measured.
    motion : str
        The reported motion: ``P1`` ... ``P16`` (period-n), ``chaos``,
        ``quasi-periodic`` or ``nonperiodic``.
    law : str, optional
        The friction law of the point, in a study over several ``laws``.
    """

    at: dict[str, float] = Field(min_length=1)
    motion: str
    law: Optional[str] = None

    @field_validator("motion")
    @classmethod
    def _known_motion(cls, v: str) -> str:
        if not re.fullmatch(r"P([1-9]|1[0-6])|chaos|quasi-periodic|nonperiodic", v):
            raise ValueError(f"motion {v!r}: expected P1 ... P16, chaos, quasi-periodic or nonperiodic")
        return v


class Study(_Strict):
    """One study: a paper figure or a user's own sweep.

    Attributes
    ----------
    name : str
    title : str
    base : dict
        The base model config (``blade_pair``, ``bladed_disk`` or ``components`` format) or
        ``{"file": "path.yaml"}`` relative to the study file.
    sweep : dict of str to Axis
        One or two swept config fields (nested names with dots).
    laws : list of str, optional
        Friction laws to run (an extra ``law`` dimension); default: the base's.
        Any registered law name (``coulomb``, ``bilinear``, ``none``, ``iwan``,
        entry points of ``blademodel.friction_laws``); the name labels the law's
        points in the result file.
    law_options : dict of str to dict, optional
        Per law of ``laws``, the ``friction_options`` of its points
        (``{iwan: {elements: 8}}``); a law not listed runs with its defaults.
    cases : list of dict
        Single points to show as four-panel case figures instead of a sweep.
    claims : list of Claim
        What the paper reports at some of the study's points; ``reproduce``
        sets each beside the measured motion (:mod:`blademodel.sweep.claims`).
    plot : str
        ``bifurcation``, ``reduction``, ``map`` or ``cases``.
    quick : dict
        Overrides for ``--quick`` (``num``, ``transient``, ``periods``).
    """

    name: str
    title: str = ""
    paper: str = Field("", description="what the paper reports for this figure")
    base: dict = Field(default_factory=dict)
    sweep: dict[str, Axis] = Field(default_factory=dict)
    laws: Optional[list[str]] = None
    law_options: Optional[dict[str, dict[str, Any]]] = None
    cases: list[dict] = Field(default_factory=list)
    claims: list[Claim] = Field(default_factory=list)
    run: RunSettings = Field(default_factory=RunSettings)
    plot: Literal["bifurcation", "reduction", "map", "cases"] = "bifurcation"
    quick: dict = Field(default_factory=lambda: {"num": 8, "transient": 40, "periods": 16})
    source: Optional[str] = Field(None, exclude=True)

    @field_validator("name")
    @classmethod
    def _plain_name(cls, v: str) -> str:
        # The name becomes file names (out/<name>/<name>.nc, figures): it must stay inside the output folder.
        if not NAME_PATTERN.fullmatch(v) or ".." in v:
            raise ValueError("a study name is a plain file name: letters, digits, '_', '-' and '.', starting "
                             "with a letter or digit, without '/' or '..'")
        return v

    @field_validator("laws")
    @classmethod
    def _known_laws(cls, v):
        from .storage import LAW_CHARS
        for name in v or []:
            registry.check_name(name)
            if len(name.encode()) > LAW_CHARS:
                raise ValueError(f"law label {name!r} is longer than {LAW_CHARS} characters; register the law "
                                 f"under a short name (entry point group {registry.ENTRY_POINT_GROUP!r})")
        if v is not None and len(set(v)) != len(v):
            raise ValueError(f"laws {v} repeat a law")
        return v

    @model_validator(mode="after")
    def _check(self):
        for law in self.law_options or {}:
            if law not in (self.laws or []):
                raise ValueError(f"law_options names {law!r}, which is not among laws {self.laws}")
        if not self.sweep and not self.cases:
            raise ValueError("a study needs a sweep or cases")
        if len(self.sweep) > 2:
            raise ValueError(f"sweep over at most two fields, got {list(self.sweep)}")
        fields = set(self.sweep) | {f for c in self.cases for f in c}
        for i, claim in enumerate(self.claims):
            if set(claim.at) - fields:
                raise ValueError(f"claims[{i}].at names {sorted(set(claim.at) - fields)}, which the study neither "
                                 f"sweeps nor sets in its cases ({sorted(fields)})")
            if claim.law is not None and claim.law not in (self.laws or [self.base.get("friction", claim.law)]):
                raise ValueError(f"claims[{i}].law = {claim.law!r} is not a law of the study")
        return self

    def quick_version(self) -> "Study":
        """The coarse version for smoke tests (fewer points and periods)."""
        q = dict(self.quick)
        num = q.pop("num", 8)
        run = self.run.model_copy(update={k: v for k, v in q.items() if k in RunSettings.model_fields})
        if run.lyapunov_periods:
            run = run.model_copy(update={"lyapunov_periods": min(run.lyapunov_periods, run.periods)})
        sweep = {k: Axis(values=list(a.grid(num))) for k, a in self.sweep.items()}
        return self.model_copy(update={"sweep": sweep, "run": run})


def _merge(parent: dict, child: dict) -> dict:
    """``child`` over ``parent``, merging nested mappings (lists are replaced)."""
    out = dict(parent)
    for k, v in child.items():
        out[k] = _merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


def load_study(path) -> Study:
    """Read a study YAML file.

    ``extends: other.yaml`` starts from another study and overrides what the file
    states (nested mappings merge: a variant can change ``base.gamma_reference``
    alone); ``base: {file: model.yaml}`` reads the base model from a file. Both
    paths are relative to the study file.
    """
    from ..config.loading import _validation_error, read_yaml
    path = Path(path)
    data, root = read_yaml(path)
    if not isinstance(data, dict):
        raise ValueError(f"{path}: a study is a mapping, got {type(data).__name__}")
    if "extends" in data:
        parent = load_study(path.parent / data.pop("extends"))
        data = _merge(parent.model_dump(exclude={"source"}), data)
    try:
        study = Study.model_validate(data)
    except Exception as e:
        from pydantic import ValidationError
        if isinstance(e, ValidationError):
            raise _validation_error(e, data, str(path), root) from None
        raise
    base = dict(study.base)
    if "file" in base:
        file_data, _ = read_yaml(path.parent / base.pop("file"))
        base = {**file_data, **base}
    return study.model_copy(update={"base": base, "source": str(path)})
