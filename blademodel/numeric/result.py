"""The result of a simulation."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


class SimulationError(RuntimeError):
    """The integration stopped early; ``result`` holds what was computed."""

    def __init__(self, message: str, result: "SimulationResult | None" = None):
        super().__init__(message)
        self.result = result


class Counters(dict):
    """The run's counters by name; a renamed counter still answers to its former name, with a warning."""

    #: Former names of counters.
    RENAMED = {"bisections": "location_substeps"}

    def __missing__(self, key):
        new = self.RENAMED.get(key)
        if new is None or new not in self:
            raise KeyError(key)
        import warnings
        warnings.warn(f"counter {key!r} is now called {new!r}", DeprecationWarning, stacklevel=2)
        return self[new]


@dataclass
class SimulationResult:
    """Time history, Poincare samples, event log and counters of one run.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Recorded times in s (the first is the start of the recorded window).
    y : ndarray, shape (n, n_state)
        Recorded states, SI units, columns named by ``state_names``.
    mode : ndarray of int, shape (n,)
        Mode index at each recorded time (``mode_names[mode]``).
    poincare_t, poincare : ndarray
        States at ``t = k T`` for every recorded period (the Poincare section).
    events : dict of str to ndarray
        ``t``, ``guard`` (name), ``from``, ``to`` (mode names) of every logged event
        in the recorded window (at most ``max_log``; ``counters["events_logged"]``
        counts all).
    counters : dict of str to int
        ``steps``, ``events``, ``location_substeps`` (the sub-steps spent locating events;
        ``bisections``, its former name, still reads it, with a warning), ``rhs_evaluations``, ...
    params : dict of str to float
        Every parameter value used.
    period : float
        The excitation period ``T`` in s.
    status : int
        A :mod:`blademodel.numeric.contract` status: 0 done, 1 non-finite state,
        2 event storm, 3 friction problem unresolved.
    message : str
    contacts : dict or None
        Per-contact kernel only: ``names``, ``modes`` (records x contacts, each
        contact's mode index), ``mode_names`` (per contact), and with
        ``record_forces`` the normal and friction forces ``N`` and ``f`` (records x
        contacts, N). ``mode``/``mode_names`` then index the combinations met.
    final_contact_modes : ndarray or None
        Per-contact kernel: each contact's mode at the end.
    """

    t: np.ndarray
    y: np.ndarray
    mode: np.ndarray
    poincare_t: np.ndarray
    poincare: np.ndarray
    events: dict
    counters: dict
    state_names: list
    mode_names: list
    params: dict
    period: float
    steps_per_period: int
    final_state: np.ndarray
    final_mode: int
    status: int = 0
    message: str = "done"
    length_scale: float | None = None
    settings: dict = field(default_factory=dict)
    contacts: dict | None = None
    final_contact_modes: np.ndarray | None = None

    def index(self, name: str) -> int:
        """Column of state ``name`` (``"x1"``, ``"vx1"``, ``"z"``)."""
        try:
            return self.state_names.index(name)
        except ValueError:
            raise KeyError(f"no state {name!r}; states are {self.state_names}") from None

    def __getitem__(self, name: str) -> np.ndarray:
        """Recorded history of state ``name``."""
        return self.y[:, self.index(name)]

    @property
    def final(self) -> dict:
        """Final state by name, SI units."""
        return dict(zip(self.state_names, map(float, self.final_state)))

    @property
    def success(self) -> bool:
        return self.status == 0
