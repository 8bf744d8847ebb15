"""A model's compiled integrator, set up once and advanced many times."""

from __future__ import annotations

import copy
import math
import warnings

import numpy as np

from ..components.force import base_frequencies
from ..model import Model
from .compiled import compile_model
from .contract import N_COUNTERS
from .methods import get_method
from .stability import certain_step, check_step, max_stable_step, mode_eigenvalues, step_is_stable



def excitation_period(model: Model) -> float:
    """``2 pi / omega`` of the model's periodic forces (they must share the base ``omega``; constant forces have none)."""
    omegas = base_frequencies(model.forces)
    if len(omegas) != 1:
        raise ValueError(f"the forces have {len(omegas)} distinct base frequencies {sorted(omegas)}; "
                         "give the period explicitly")
    return 2 * math.pi / omegas.pop()


#: Finest event tolerance (a fraction of the step) that double precision resolves everywhere in a step:
#: a finer one is accepted with a warning, and the bracket stops at the resolution.
EVENT_TOL_FLOOR = 1e-15


def check_settings(steps_per_period, event_tol, max_events_per_step) -> None:
    """Validate the settings every kernel shares; raise ``ValueError`` naming the bad one."""
    from .limits import check_integer
    for name, value in (("steps_per_period", steps_per_period), ("max_events_per_step", max_events_per_step)):
        check_integer(name, value, 1)   # also refuses inf, NaN and booleans (int(inf) would raise OverflowError)
    if not (event_tol > 0 and math.isfinite(event_tol)):
        raise ValueError(f"event_tol = {event_tol!r} must be a positive number")
    if event_tol < EVENT_TOL_FLOOR:
        warnings.warn(f"event_tol = {event_tol!r} is below what double precision resolves within a step "
                      f"(about {EVENT_TOL_FLOOR:g} of it); events are located to that resolution instead",
                      stacklevel=3)


#: How a kernel shrinks an event's bracket (``event_location``).
EVENT_LOCATIONS = ("bisection", "predicted")


def check_event_location(value) -> str:
    """``value`` if it names a way of locating events, else ``ValueError`` naming it."""
    if value not in EVENT_LOCATIONS:
        raise ValueError(f"event_location = {value!r} must be one of {', '.join(EVENT_LOCATIONS)}")
    return value


def state_vector(names: list, n_state: int, y0=None) -> np.ndarray:
    """State vector from ``y0`` (array or ``{name: value}``); default rest."""
    y = np.zeros(n_state)
    if y0 is None:
        return y
    if isinstance(y0, dict):
        for k, v in y0.items():
            if k not in names:
                raise KeyError(f"y0 names unknown state {k!r}; states are {names}")
            y[names.index(k)] = v
    else:
        y0 = np.asarray(y0, dtype=float)
        y[: y0.size] = y0
    return y


def _what(a) -> str:
    """Short description of an argument for error messages."""
    if isinstance(a, np.ndarray):
        return f"a {a.dtype} array of shape {a.shape}"
    return f"{type(a).__name__} {a!r}"[:80]


def _check_array(name: str, a, template: np.ndarray, rows: int | None) -> int:
    """``a`` matches ``template``'s dtype and trailing shape, writable, C-contiguous, with ``>= rows`` rows."""
    if not (isinstance(a, np.ndarray) and a.dtype == template.dtype and a.ndim == template.ndim
            and a.shape[1:] == template.shape[1:] and a.flags.c_contiguous and a.flags.writeable
            and (rows is None or a.shape[0] >= rows)):
        want = f"a writable C-contiguous {template.dtype} array of shape ({'n' if rows is None else f'>= {rows}'}" \
               + "".join(f", {k}" for k in template.shape[1:]) + ("," if template.ndim == 1 else "") + ")"
        raise ValueError(f"advance: {name} must be {want}, got {_what(a)}")
    return a.shape[0]


def _check_buffers(name: str, arrays, templates: tuple) -> int:
    """A tuple of arrays like ``templates``, each with at least as many rows as the first; its row count."""
    if not isinstance(arrays, (tuple, list)) or len(arrays) != len(templates):
        raise ValueError(f"advance: {name} must be a tuple of {len(templates)} arrays (see {name}_buffer), "
                         f"got {_what(arrays)}")
    rows = _check_array(f"{name}[0]", arrays[0], templates[0], None)
    for i, (a, tpl) in enumerate(zip(arrays[1:], templates[1:]), 1):
        _check_array(f"{name}[{i}]", a, tpl, rows)
    return rows


def check_advance_arguments(integ: "Integrator", y, mode, start_period, end_period, n_transient=None, *,
                            record=None, poincare=None, log=None, counters=None, record_every=1,
                            stats=None, forces=None) -> None:
    """Validate the arguments of an integrator's ``advance`` before they reach compiled code.

    The kernels trust their arguments: a short state, a mode number out of range
    or a buffer of the wrong shape would be read or written out of bounds and
    return status 0 with garbage. This check costs microseconds per call.

    Parameters
    ----------
    integ : Integrator
        The integrator whose ``advance`` is called (its kernel, state size and modes).
    y, mode, start_period, end_period, n_transient, record, poincare, log, counters, record_every
        The arguments of ``advance``.
    stats, forces : optional
        Those of :meth:`ContactIntegrator.advance <blademodel.numeric.contact_kernel.ContactIntegrator.advance>`.

    Raises
    ------
    ValueError
        Naming the argument, what it must be and what it is.
    """
    from .limits import check_integer
    n = integ.n_state
    if not (isinstance(y, np.ndarray) and y.dtype == np.float64 and y.shape == (n,) and y.flags.c_contiguous
            and y.flags.writeable):
        raise ValueError(f"advance: y must be a writable C-contiguous float64 array of shape ({n},) "
                         f"(the state {', '.join(integ.meta['state'])}), got {_what(y)}")
    if integ.kernel == "contact":
        per_contact = integ.meta["contact_modes"]
        cm = np.asarray(mode)
        if cm.shape != (len(per_contact),) or not (np.issubdtype(cm.dtype, np.integer) and cm.dtype != np.bool_):
            raise ValueError(f"advance: mode must hold one integer per contact ({len(per_contact)}), "
                             f"got {_what(mode)}")
        for j, (m, names) in enumerate(zip(cm, per_contact)):
            if not 0 <= m < len(names):
                raise ValueError(f"advance: mode[{j}] = {int(m)} is not a mode of contact "
                                 f"{integ.meta['contacts'][j]!r} (0..{len(names) - 1}: {', '.join(names)})")
    else:
        names = integ.meta["modes"]
        if not isinstance(mode, (int, np.integer)) or isinstance(mode, (bool, np.bool_)) \
                or not 0 <= mode < len(names):
            raise ValueError(f"advance: mode = {mode!r} is not a mode number "
                             f"(0..{len(names) - 1}: {', '.join(names)})")
    start = check_integer("advance: start_period", start_period, 0)
    end = check_integer("advance: end_period", end_period, start)
    first = start if n_transient is None else check_integer("advance: n_transient", n_transient, 0)
    check_integer("advance: record_every", record_every, 1)
    n_rec = 0
    if record is not None:
        n_rec = _check_buffers("record", record, integ.record_buffer(1))
    if forces is not None:
        nc = integ.nc
        _check_buffers("forces", forces, (np.empty((1, nc)), np.empty((1, nc))))
        if forces[0].shape[0] != n_rec or forces[1].shape[0] != n_rec:
            raise ValueError(f"advance: forces must have as many rows as the record ({n_rec})")
    if poincare is not None:
        _check_array("poincare", poincare, np.empty((1, n)), max(end - first, 0))
    if log is not None:
        _check_buffers("log", log, integ.log_buffer(1))
    if counters is not None:
        _check_array("counters", counters, np.empty(1, dtype=np.int64), N_COUNTERS)
    if stats is not None:
        from .contract import N_STATS
        _check_array("stats", stats, np.empty(1), N_STATS)


def goes_on(run_end, start_period: int, period: float, y: np.ndarray, mode) -> bool:
    """Whether a call of ``advance`` from ``(y, mode)`` at ``start_period`` goes on from where the last run ended,
    ``run_end = (t, y, mode)`` (None: no run, or one whose hybrid state need not be kept): the kernels keep such a
    run's hybrid state (guards read from their boundaries) only then."""
    return run_end is not None and abs(run_end[0] - start_period * period) <= 1e-9 * period \
        and np.array_equal(run_end[2], mode) and np.array_equal(run_end[1], y)


def checked_parameter_values(p_raw, names) -> np.ndarray:
    """``p_raw`` as floats, one finite value for each parameter of ``names`` (``with_parameter_values``).

    Raises
    ------
    ValueError
        Naming the parameters, if it is not.
    """
    p_raw = np.array(p_raw, dtype=float)
    if p_raw.shape != (len(names),) or not np.all(np.isfinite(p_raw)):
        raise ValueError(f"p_raw must hold {len(names)} finite values (one per parameter: "
                         f"{', '.join(names)}), got {p_raw!r}")
    return p_raw


class StructureMismatch(ValueError):
    """A model given to :meth:`Integrator.with_parameters` differs in more than parameter values."""


class Integrator:
    """What every kernel's integrator shares: the model, the step settings, the state layout.

    Subclasses set ``meta["state"]`` and ``n_state`` and implement ``mode_of``,
    ``record_buffer`` and ``advance``.
    """

    #: Which kernel integrates (``"product"`` or ``"contact"``).
    kernel = ""

    def _settings(self, model: Model, steps_per_period, event_tol, max_events_per_step, period,
                  check_stability: bool = True) -> None:
        check_settings(steps_per_period, event_tol, max_events_per_step)
        self.model = model
        self.period = excitation_period(model) if period is None else float(period)
        self._explicit_period = period is not None
        self._check_stability = bool(check_stability)
        self.steps_per_period = int(steps_per_period)
        self.event_tol = float(event_tol)
        self.max_events_per_step = int(max_events_per_step)

    def with_parameters(self, model: Model) -> "Integrator":
        """This integrator for ``model``, which differs from its own in parameter values only.

        Nothing is generated or compiled: the copy takes ``model``'s parameter values
        (and its excitation period, unless the period was given explicitly) and checks
        the step's stability again. Continuation moves a parameter at every correction.

        Raises
        ------
        StructureMismatch
            If ``model`` has another structure (other components, laws or modes).
        StepTooLargeError
            If the step is unstable with the new parameters.
        """
        if model.structure_key() != self.model.structure_key():
            raise StructureMismatch("with_parameters needs a model of the same structure "
                                    "(only parameter values may differ)")
        new = self._with_values_of(model, None if self._explicit_period else excitation_period(model))
        new.model = model
        return new

    def _with_values_of(self, model: Model, period: float | None) -> "Integrator":
        """A copy with ``model``'s parameter values and ``period`` (None: this one's), stability checked."""
        raise NotImplementedError

    @property
    def state_names(self) -> list[str]:
        return list(self.meta["state"])

    def _structural(self, key: str, make):
        """``make()``, once: the model's structure fixes it, so it is kept, and shared by the copies made for other
        values of the parameters."""
        found = self.__dict__.get(key)
        if found is None:
            found = self.__dict__[key] = make()
        return found

    @property
    def discrete_states(self) -> np.ndarray:
        """Positions of the friction laws' ``discrete_states`` in the state vector (whole-number labels that only
        resets set: a periodic orbit holds them as part of its mode, :mod:`blademodel.orbits`)."""
        return self._structural("_discrete_states",
                                lambda: np.array(self.model.discrete_state_indices(), dtype=np.int64))

    @property
    def law_states(self) -> np.ndarray:
        """Positions of all the friction laws' states in the state vector (:meth:`~blademodel.model.Model.
        law_state_indices`), the discrete ones among them."""
        return self._structural("_law_states", lambda: np.array(self.model.law_state_indices(), dtype=np.int64))

    @property
    def continuous_law_states(self) -> np.ndarray:
        """:attr:`law_states` but the :attr:`discrete_states`."""
        return self._structural("_continuous_law_states",
                                lambda: np.setdiff1d(self.law_states, self.discrete_states))

    def worker(self) -> "Integrator":
        """This integrator with work arrays of its own, to run in another thread.

        The copy shares the compiled kernel, the model and the parameter tables (which
        a run only reads) and owns every array a run writes to, so the two may
        integrate at the same time: the kernels release the GIL while they integrate.
        Each copy gives the same results as this integrator, to the bit.
        """
        new = copy.copy(self)
        new._own_work_arrays()
        return new

    def _own_work_arrays(self) -> None:
        raise NotImplementedError

    def initial_state(self, y0=None) -> np.ndarray:
        """State vector from ``y0`` (array or ``{name: value}``); default rest."""
        return state_vector(self.meta["state"], self.n_state, y0)


class HybridIntegrator(Integrator):
    """Fixed-step RK4 with located events for one model and one set of settings.

    Construction compiles (or loads) the kernel, evaluates the parameter array and
    checks the step against RK4's stability limit; :meth:`advance` then integrates
    whole excitation periods with no set-up cost.

    Parameters
    ----------
    model : Model
    steps_per_period : int
        ``h = T / steps_per_period``.
    event_tol : float
        Events are bracketed to ``event_tol * h``; ``>= 1`` switches at the end of
        the step instead (no location, first order; for comparison).
    method : {"rk4", "rk8"}
        Stepping method (:mod:`~blademodel.numeric.methods`): classical RK4 (fused)
        or an eighth-order Runge-Kutta method (12 stages a step).
    event_location : {"bisection", "predicted"}
        How the bracket is shrunk: by bisection (about ``log2(1 / event_tol)``
        sub-steps an event, the default here, which reproduces the paper pair's
        published results bit for bit) or from predicted roots (chord and secants,
        about 5; the same roots to ``event_tol``; ``docs/solver.md``).
    max_events_per_step : int
        Cap on events in one step (an event storm stops the run).
    energy : bool
        Integrate the work and dissipation accumulators too.
    period : float, optional
        Excitation period; by default from the model's forces.
    check_stability : bool
        Refuse a step above RK4's stability limit (:class:`StepTooLargeError`).
    """

    def __init__(self, model: Model, *, steps_per_period: int = 1000, event_tol: float = 1e-10,
                 max_events_per_step: int = 100, energy: bool = False, period: float | None = None,
                 check_stability: bool = True, event_location: str = "bisection", method: str = "rk4"):
        self._settings(model, steps_per_period, event_tol, max_events_per_step, period, check_stability)
        self.event_location = check_event_location(event_location)
        self.method = get_method(method)
        # classical RK4 runs fused (an empty tableau); another method steps by its tableau
        self._tableau = np.zeros(0) if method == "rk4" else self.method.tableau()
        self.compiled = compile_model(model, energy=energy)
        self.module, self.meta = self.compiled.module, self.compiled.meta
        self.p_raw = np.array([model.parameters[n] for n in self.meta["params"]], dtype=float)
        self.p = self.module.derived(self.p_raw)
        self.n_state = self.meta["n_state"]
        self.n_physical = self.n_state - (3 if energy else 0)
        self._check_step()
        self._eig_cache: dict = {}   # shared by the copies of with_parameter_values
        self._g = np.empty(self.module.GUARD_DIR.shape[1] + 1)
        self._ytmp = np.empty(self.n_state)
        self._goff = np.zeros_like(self._g)   # the kernel's drift offsets where the last run ended
        self._run_end = None
        self._empty_rec = (np.empty(0), np.empty((0, self.n_state)), np.empty(0, dtype=np.int64))
        self._empty_log = (np.empty(0), np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64),
                           np.empty(0, dtype=np.int64))

    kernel = "product"

    def _check_step(self) -> None:
        """Refuse a step above the method's stability limit in any mode (unless ``check_stability`` is off)."""
        if self._check_stability:
            h_max, which = max_stable_step(self.module.jacobian, len(self.meta["modes"]), self.p_raw,
                                           self.n_physical, self.method.amplification)
            check_step(self.period, self.steps_per_period, h_max,
                       self.meta["modes"][which] if which >= 0 else "-", self.method.name)

    def _own_work_arrays(self) -> None:
        self._g = np.empty_like(self._g)
        self._ytmp = np.empty_like(self._ytmp)
        self._goff = np.zeros_like(self._goff)
        self._run_end = None

    def _with_values_of(self, model: Model, period: float | None) -> "HybridIntegrator":
        return self.with_parameter_values([model.parameters[n] for n in self.meta["params"]], period)

    def with_parameter_values(self, p_raw, period: float | None = None) -> "HybridIntegrator":
        """This integrator with the raw parameter values ``p_raw`` (in ``meta["params"]`` order).

        The cheap form of :meth:`with_parameters` for callers that know the values
        already (continuation, which moves one config field at every correction): no
        model is built or compared. ``period`` is the new excitation period (ignored
        if the period was given explicitly; ``None`` keeps it). The copy's ``model``
        stays the one this integrator was built from: its structure, not these
        values. The step's stability is checked as in :meth:`with_parameters`; the
        modes' eigenvalues depend only on the parameters in their Jacobians
        (``JACOBIAN_PARAMS`` of the generated module), and are computed once for each
        set of their values and shared by every copy.

        Raises
        ------
        ValueError
            If ``p_raw`` does not hold one finite value per parameter.
        StepTooLargeError
            If the step is unstable with the new parameters.
        """
        p_raw = checked_parameter_values(p_raw, self.meta["params"])
        new = copy.copy(self)
        new.p_raw = p_raw
        new.p = self.module.derived(p_raw.tolist())   # Python floats: the generated formulas run twice as fast
        if period is not None and not self._explicit_period:
            new.period = float(period)
        new._own_work_arrays()
        if self._check_stability:
            # the step itself inside the stability region in every mode settles it; the limit
            # (a bisection on each eigenvalue's ray) is only needed for the error message
            h = new.period / new.steps_per_period
            lam, h_certain = new._eigenvalues()
            if h > h_certain and not step_is_stable(h, lam, self.method.amplification):
                new._check_step()
        return new

    def _eigenvalues(self) -> tuple[np.ndarray, float]:
        """Every mode's :func:`~blademodel.numeric.stability.physical_eigenvalues` at this integrator's parameters,
        and the step below which all of them are certainly stable (:func:`~blademodel.numeric.stability.certain_step`)."""
        used = getattr(self.module, "JACOBIAN_PARAMS", None)
        key = None if used is None else tuple(self.p_raw[list(used)].tolist())
        found = self._eig_cache.get(key) if key is not None else None
        if found is None:
            lam = mode_eigenvalues(self.module.jacobian, len(self.meta["modes"]), self.p_raw, self.n_physical)[0]
            h = certain_step(lam, self.method.amplification_coefficients()) * (1.0 - 1e-9)
            if np.isfinite(h) and not step_is_stable(h, lam, self.method.amplification):
                h = 0.0   # the roots were not accurate enough: every step is checked by evaluation
            found = (lam, h)
            if key is not None:
                if len(self._eig_cache) > 64:
                    self._eig_cache.clear()
                self._eig_cache[key] = found
        return found

    @property
    def mode_names(self) -> list[str]:
        return list(self.meta["modes"])

    def record_buffer(self, n_records: int) -> tuple:
        """``(t, y, mode)`` arrays for ``n_records`` records (``advance(record=...)``)."""
        return np.empty(n_records), np.empty((n_records, self.n_state)), np.empty(n_records, dtype=np.int64)

    def log_buffer(self, n: int) -> tuple:
        """``(t, guard, from, to)`` arrays for an event log of ``n`` entries (``advance(log=...)``)."""
        return (np.empty(n), *(np.empty(n, dtype=np.int64) for _ in range(3)))

    def named_events(self, log: tuple, n: int) -> dict:
        """The first ``n`` entries of ``log`` by name: ``t``, ``guard``, ``from`` and ``to`` modes."""
        modes, guards = self.meta["modes"], self.meta["guards"]
        log_t, log_guard, log_from, log_to = log
        return {"t": log_t[:n].copy(),
                "guard": [guards[f][gi] for f, gi in zip(log_from[:n], log_guard[:n])],
                "from": [modes[i] for i in log_from[:n]],
                "to": [modes[i] for i in log_to[:n]]}

    def mode_table(self, rec_mode: np.ndarray, final_mode) -> tuple[list, np.ndarray, int]:
        """Mode names, the recorded modes as indices into them, and the final mode's index."""
        return list(self.meta["modes"]), rec_mode, int(final_mode)

    def mode_of(self, y: np.ndarray, t: float = 0.0) -> int:
        """The mode a state belongs to (closed contacts where ``delta >= 0``).

        May apply the entry resets of the friction laws to ``y`` (a Jenkins
        stretch, a stick projection), in place.
        """
        return int(self.module.initial_mode(t, y, self.p, self._g, self._ytmp))

    def advance(self, y: np.ndarray, mode: int, start_period: int, end_period: int, *,
                n_transient: int | None = None, record=None, poincare=None, log=None,
                counters=None, record_every: int = 1, check: bool = True) -> tuple[int, int, float]:
        """Integrate periods ``start_period`` to ``end_period``; ``y`` is updated in place.

        Parameters
        ----------
        y : ndarray
        mode : int
        start_period, end_period : int
            Time runs from ``start_period * T`` to ``end_period * T``.
        n_transient : int, optional
            Periods before this one are not recorded (default: ``start_period``).
        record : tuple of arrays, optional
            ``(t, y, mode)`` arrays to fill with states every ``record_every`` steps.
        poincare : ndarray, optional
            Filled with the state at the end of each recorded period.
        log : tuple of arrays, optional
            ``(t, guard, from, to)`` arrays for the event log.
        counters : ndarray of int64, optional
            Accumulates steps, events, location sub-steps, rhs evaluations, log and record
            positions; pass the same array to consecutive calls.

        check : bool
            Validate the arguments first (:func:`check_advance_arguments`: ~0.06 ms). Only
            a caller whose arrays come from this integrator (``initial_state``,
            ``record_buffer``, ``log_buffer``) and whose mode it returned may skip it
            (the period map, which runs the kernel for every correction).

        Returns
        -------
        status, mode, t : int, int, float

        Raises
        ------
        ValueError
            For an argument the kernel cannot take (:func:`check_advance_arguments`).
        """
        if check:
            check_advance_arguments(self, y, mode, start_period, end_period, n_transient, record=record,
                                    poincare=poincare, log=log, counters=counters, record_every=record_every)
        if counters is None:
            counters = np.zeros(N_COUNTERS, dtype=np.int64)
        rec_t, rec_y, rec_mode = record if record is not None else self._empty_rec
        log_t, log_g, log_f, log_to = log if log is not None else self._empty_log
        if poincare is None:
            # rows from the first recorded period on (n_transient = 0 is a period, not 'unset')
            first = start_period if n_transient is None else n_transient
            poincare = np.empty((max(end_period - first, 0), self.n_state))
        # A friction guard a transition left a rounding error on its wrong side is read from its boundary until
        # the next transition (loop.drift_offsets): hybrid state of the run, kept only where a call goes on from
        # the state and mode where the last one ended, as the per-contact kernel keeps its marks.
        carry = goes_on(self._run_end, start_period, self.period, y, mode)
        status, mode, t, drifting = self.module.integrate(
            y, int(mode), self.p, self.period, self.steps_per_period, int(start_period), int(end_period),
            int(start_period if n_transient is None else n_transient), int(record_every), self.event_tol,
            self.max_events_per_step, self.event_location == "predicted", self._tableau, rec_t, rec_y, rec_mode,
            poincare, log_t, log_g, log_f, log_to, counters, self._goff, carry)
        # only a run that ends with offsets set has any to hand on
        self._run_end = (t, y.copy(), mode) if status == 0 and drifting else None
        return int(status), int(mode), float(t)
