"""A model: a validated collection of components."""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from functools import cached_property

from .components import Contact, Damper, Mass, Spring
from .components.force import Force


@dataclass(frozen=True, eq=False)
class Model:
    """Masses and the components acting on them.

    Parameters
    ----------
    masses : sequence of Mass
    springs, dampers, contacts : sequence of the matching components
    forces : sequence of ConstantForce, HarmonicForce or MultiHarmonicForce
    name : str
        A label for outputs.
    """

    masses: tuple[Mass, ...]
    springs: tuple[Spring, ...] = ()
    dampers: tuple[Damper, ...] = ()
    forces: tuple[Force, ...] = ()
    contacts: tuple[Contact, ...] = ()
    name: str = "model"

    def __post_init__(self):
        for f in ("masses", "springs", "dampers", "forces", "contacts"):
            object.__setattr__(self, f, tuple(getattr(self, f)))
        if not self.masses:
            raise ValueError("a model needs at least one mass")
        names = [m.name for m in self.masses]
        if len(set(names)) != len(names):
            raise ValueError(f"mass names must be unique, got {names}")
        coords = set(self.coordinates)
        for comp in (*self.springs, *self.dampers):
            for c in comp.coordinates:
                if c not in coords:
                    raise ValueError(f"{type(comp).__name__.lower()} refers to coordinate {c!r}, "
                                     f"which no mass has (known: {sorted(coords)})")
        by_name = {m.name: m for m in self.masses}
        for comp in self.forces:
            if by_name.get(comp.mass.name) != comp.mass:
                raise ValueError(f"force acts on mass {comp.mass.name!r}, which is not in the model")
        cnames = [c.name for c in self.contacts]
        if len(set(cnames)) != len(cnames):
            raise ValueError(f"contact names must be unique, got {cnames}")
        for c in self.contacts:
            for b in c.bodies:
                if by_name.get(b.name) != b:
                    raise ValueError(f"contact {c.name} touches mass {b.name!r}, which is not in the model")
        reserved = {"t", *coords, *(f"v{c}" for c in coords),
                    *(st for c in self.contacts for st in c.friction.states),
                    *(f"{st}_{c.name}" for c in self.contacts for st in c.friction.states),
                    *(f"{x}_{c.name}" for c in self.contacts for x in ("f", "N"))}
        clash = sorted(reserved & set(self.parameters))  # also raises on conflicting shared parameters
        if clash:
            raise ValueError(f"parameter name(s) {clash} clash with state, time or force symbols; rename them")

    @property
    def components(self) -> tuple:
        return (*self.masses, *self.springs, *self.dampers, *self.forces, *self.contacts)

    @property
    def length_scale(self) -> float | None:
        """Scale of non-dimensional displacements, ``X1 = x1 / gap``: the first gapped contact's gap.

        ``None`` without gapped contacts or with a zero gap (then outputs stay in metres).
        """
        gaps = [c.parameters()["gap"].value for c in self.contacts if "gap" in c.parameters()]
        return (gaps[0] if gaps else 0.0) or None

    @property
    def coordinates(self) -> tuple[str, ...]:
        """Coordinate names in state order (mass by mass, ``x`` before ``y``)."""
        return tuple(c for m in self.masses for c in m.coordinates)

    def law_state_labels(self) -> list[tuple[str, str, str]]:
        """The friction laws' states in state-vector order: ``(label, contact name, state name)`` each.

        The label is the state's name, or ``<name>_<contact>`` where the laws of two
        contacts have a state of that name (every kernel names the state vector so).
        """
        names = [st for c in self.contacts for st in c.friction.states]
        return [(st if names.count(st) == 1 else f"{st}_{c.name}", c.name, st)
                for c in self.contacts for st in c.friction.states]

    def law_state_indices(self) -> list[int]:
        """Positions in the physical state vector (coordinates, velocities, law states) of the friction laws'
        states, in the order of :meth:`law_state_labels`."""
        first = 2 * len(self.coordinates)
        return list(range(first, first + len(self.law_state_labels())))

    def discrete_state_indices(self) -> list[int]:
        """Positions in the physical state vector of the laws' ``discrete_states``: labels that only resets
        set, held as part of a periodic orbit's mode."""
        by_contact = {c.name: set(c.friction.discrete_states) for c in self.contacts}
        return [i for i, (_, c, st) in zip(self.law_state_indices(), self.law_state_labels()) if st in by_contact[c]]

    @cached_property
    def parameters(self) -> dict[str, float]:
        """Every numeric parameter by symbol name, in a fixed order."""
        out: dict[str, float] = {}
        params = []
        for comp in self.components:
            params += list(comp.parameters().values())
        for c in self.contacts:
            params += list(c.friction.parameters().values())
        for p in params:
            if p.name in out and out[p.name] != p.value:
                raise ValueError(f"parameter {p.name} is shared with two values: {out[p.name]} and {p.value}; "
                                 f"components given plain numbers take default names, so name one of them "
                                 f"explicitly, e.g. Param('{p.name}_2', {p.value})")
            out[p.name] = p.value
        return out

    def structure(self) -> dict:
        """Everything that fixes the equations' form, without numeric values."""
        def pnames(comp):
            return {k: v.name for k, v in comp.parameters().items()}
        return {
            "masses": [(m.name, m.dofs, pnames(m)) for m in self.masses],
            "springs": [(s.a, s.b, pnames(s)) for s in self.springs],
            "dampers": [(d.a, d.b, pnames(d)) for d in self.dampers],
            "forces": [(type(f).__name__, f.mass.name, pnames(f)) for f in self.forces],
            "contacts": [(c.name, c.body1.name, c.body2.name if c.body2 else None, pnames(c),
                          [str(x) for x in c.friction.structure()]) for c in self.contacts],
        }

    def structure_key(self) -> str:
        """A hash of :meth:`structure`: models with equal keys share compiled code."""
        text = json.dumps(self.structure(), sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:16]
