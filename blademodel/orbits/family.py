"""The period maps of one config field's values: built once, then the integrator's parameters changed."""


from __future__ import annotations


import numpy as np

from .field_path import AffineFieldPath
from .period_map import PeriodMap, worker_count


class _Family:
    """Period maps of the config at any value of the field (integrators made on demand, a few kept).

    The field is set as ``--set`` does (:func:`~blademodel.config.apply_overrides`): a
    top-level field, a dotted path (``contacts.0.gap``), or in the components format
    a declared parameter by its bare name (``omega``).
    """

    def __init__(self, config, name: str, periods: int, settings: dict, start: float, jacobian: str = "auto",
                 bounds: tuple | None = None, workers: int | None = None):
        self.config, self.name, self.periods, self.settings = config, name, periods, settings
        self.jacobian = jacobian
        self.workers = worker_count(workers)
        try:
            self.config_at(start)
        except ValueError as e:
            raise ValueError(f"{type(config).__name__} has no field {name!r} to continue in, or {start!r} is not "
                             f"a value it takes: {e}") from None
        for end in bounds or ():
            try:
                self.config_at(end)
            except ValueError as e:
                raise ValueError(f"{name} = {end!r}, an end of the range, is not a value {type(config).__name__} "
                                 f"takes ({e}): end the range inside the values it takes (at its bound, say: the "
                                 f"branch lands on the end of the range where the field takes no values past "
                                 f"it)") from None
        self._cache: dict = {}
        self._log_size = 64      # the event log's entries a new map's runs start with (the most its maps needed)
        self._dropped = (0, 0)   # integrations and replays of the maps no longer kept
        self._first = None
        self.first_value = None   # the field's value the first integrator was built at
        self._bounds = (min(bounds), max(bounds)) if bounds is not None else None
        self._path: AffineFieldPath | None = None
        self._probed = False
        self.symmetry = None   # a tuned ring's CyclicSymmetry: the maps are then the reduced ones (.cyclic)

    def reduce_by(self, symmetry) -> None:
        """Make the maps from here on the ones reduced by a tuned ring's ``symmetry`` (:mod:`.cyclic`)."""
        self.symmetry = symmetry
        self._cache.clear()

    def config_at(self, value: float):
        from ..config import apply_overrides
        return apply_overrides(self.config, {self.name: float(value)}, source="continuation")

    def admits(self, value: float) -> bool:
        """Whether the config takes ``value`` in the field (``mu`` takes no value below 0, ``omega`` none at 0)."""
        try:
            self.config_at(value)
        except ValueError:
            return False
        return True

    def _values_at(self, value: float) -> tuple[np.ndarray, float | None]:
        """The raw parameters and excitation period of the model built at ``value`` (same structure as the first)."""
        from ..numeric.integrator import excitation_period
        model = self.config_at(value).build()
        if model.structure_key() != self._first.model.structure_key():
            raise ValueError(f"{self.name} = {value:g} changes the model's structure")
        try:
            period = excitation_period(model)
        except ValueError:
            period = None
        return np.array([model.parameters[k] for k in self._first.meta["params"]], dtype=float), period

    def path(self) -> AffineFieldPath | None:
        """The field's affine path over the range widened by a quarter each side (or the range itself), if any.

        Only for integrators that take parameter values directly
        (``with_parameter_values``), once the first one exists.
        """
        if not self._probed and self._first is not None and self._bounds is not None \
                and hasattr(self._first, "with_parameter_values"):
            self._probed = True
            lo, hi = self._bounds
            if hi > lo:
                wide = 0.25 * (hi - lo)
                self._path = (AffineFieldPath.probe(self._values_at, lo - wide, hi + wide)
                              or AffineFieldPath.probe(self._values_at, lo, hi))
        return self._path

    def parameter_direction(self, value: float, delta: float, names: list) -> tuple[np.ndarray, float]:
        """``d p / d lambda`` over the raw parameters ``names`` and ``d T / d lambda`` at ``value``.

        From the field's affine path where it has one (:mod:`.field_path`), else
        central differences of the built models' parameter values and excitation
        periods (no integration): a field enters the parameters through the config's
        own formulas, which are smooth (most are linear).
        """
        path = self.path()
        if path is not None and path.covers(value) and list(names) == list(self._first.meta["params"]):
            return path.derivative(value)
        from ..numeric.integrator import excitation_period
        out = []
        for v in (value + delta, value - delta):
            model = self.config_at(v).build()
            out.append((np.array([model.parameters[k] for k in names], dtype=float), excitation_period(model)))
        return (out[0][0] - out[1][0]) / (2 * delta), (out[0][1] - out[1][1]) / (2 * delta)

    def map_at(self, value: float) -> PeriodMap:
        """The period map at ``value`` (the first integrator's parameters changed, where the kernel allows)."""
        key = float(value)
        if key not in self._cache:
            # the event log's size the maps so far needed: a new map that starts smaller integrates its first run
            # twice
            self._log_size = max([self._log_size] + [P.log_size for P in self._cache.values()])
            if len(self._cache) > 8:
                old = self._cache.pop(next(iter(self._cache)))
                self._dropped = (self._dropped[0] + old.evaluations, self._dropped[1] + old.replays)
            # reduced, the map covers T / d; the orbits' period (self.periods) is the symmetry's
            self._cache[key] = PeriodMap(self._integrator_at(key), 1 if self.symmetry else self.periods,
                                         self.jacobian, self.workers, symmetry=self.symmetry,
                                         log_size=self._log_size)
        return self._cache[key]

    @property
    def discrete(self) -> np.ndarray:
        """Positions of the friction laws' discrete states (:attr:`.period_map.PeriodMap.discrete`), once a period
        map exists."""
        return self._first.discrete_states

    def state_names(self) -> list:
        """The names of the integrator's states (once a period map exists)."""
        return list(self._first.meta["state"])

    def twin(self) -> "_Family":
        """A family of its own period maps (and integrators, and work arrays) that gives the same maps to the bit:
        its first integrator is built at this one's first value, so that both move from it alike."""
        twin = _Family(self.config, self.name, self.periods, self.settings, self.first_value, self.jacobian,
                       bounds=self._bounds, workers=1)
        twin.reduce_by(self.symmetry)
        twin.map_at(self.first_value)
        return twin

    def work(self) -> tuple[int, int]:
        """The integrations and tangent replays of every period map made so far."""
        maps = self._cache.values()
        return (self._dropped[0] + sum(P.evaluations for P in maps),
                self._dropped[1] + sum(P.replays for P in maps))

    def _integrator_at(self, value: float):
        """An integrator at ``value``: the first one with the path's parameter values, its parameters taken from
        the model built at ``value``, or (another structure) a new one."""
        from ..numeric.integrator import StructureMismatch
        from ..numeric.kernels import make_integrator
        if self.symmetry is not None and self._first is not None:
            # moved from the reduced first integrator, the copies are reduced ones: the whole period's tables
            # (the forcing's phase table among them) are not packed for every value
            self._first = self.symmetry.reduced(self._first)
        path = self.path()
        if path is not None and path.covers(value):
            return self._first.with_parameter_values(*path.at(value))
        model = self.config_at(value).build()
        if self._first is not None:
            try:
                return self._first.with_parameters(model)
            except StructureMismatch:
                pass
        self._first = make_integrator(model, **self.settings)
        self.first_value = float(value)
        self._probed = False
        return self._first
