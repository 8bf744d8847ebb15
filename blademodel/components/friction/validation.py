"""Checks of a friction law against the interface of :mod:`.base`, before any code is generated.

A law written outside the package reaches the symbolic layer and the code
generators only through :class:`~.base.FrictionLaw`'s methods. A law with no
closed mode, or one whose ``force`` returns ``None``, used to fail deep inside
them (a ``TypeError`` in the assembly, or generated code written to the kernel
cache that could not run). :func:`check_law` calls every method once per mode
with a context of plain symbols and checks what comes back, so such a law is
refused when its :class:`~blademodel.components.contact.Contact` is built, with a
message that names the law, the method and the offending value.
"""

from __future__ import annotations

import inspect
from collections.abc import Iterable, Mapping
from typing import Any

from .._sympy import sp
from ..parameter import Param
from .base import Candidate, ContactContext, FrictionLaw, Guard, StickConstraint

#: Laws already checked, by class and :meth:`FrictionLaw.structure` (the structure fixes the expressions).
_CHECKED: set = set()


class FrictionLawError(ValueError):
    """A friction law that does not keep the :class:`~.base.FrictionLaw` interface.

    The message starts with ``friction law <module:Class>:`` and names the method
    and the value at fault.
    """


def law_label(law_or_cls) -> str:
    """``"module:Class"`` of a law instance or class."""
    cls = law_or_cls if isinstance(law_or_cls, type) else type(law_or_cls)
    return f"{cls.__module__}:{cls.__qualname__}"


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def check_law_class(cls: type, label: str | None = None) -> type:
    """Refuse a class that is not a concrete :class:`FrictionLaw` subclass.

    Parameters
    ----------
    cls : type
    label : str, optional
        How the law was named (its registered name or import path).

    Raises
    ------
    FrictionLawError
    """
    name = label or (law_label(cls) if isinstance(cls, type) else repr(cls))
    if not (isinstance(cls, type) and issubclass(cls, FrictionLaw)):
        raise FrictionLawError(f"friction law {name}: {_short(cls)} is not a FrictionLaw subclass")
    if inspect.isabstract(cls):
        missing = ", ".join(sorted(cls.__abstractmethods__))
        raise FrictionLawError(f"friction law {name}: {cls.__name__} does not implement {missing} "
                               f"(abstract methods of FrictionLaw)")
    return cls


def _is_expr(x: Any) -> bool:
    return (isinstance(x, sp.Expr) or isinstance(x, (int, float))) and not isinstance(x, bool)


def _is_condition(x: Any) -> bool:
    return isinstance(x, (bool, sp.logic.boolalg.Boolean))


class _Checker:
    """Checks of one law instance; every failure is a :class:`FrictionLawError` naming the law."""

    def __init__(self, law: FrictionLaw):
        self.law = law
        self.name = law_label(law)

    def fail(self, what: str) -> FrictionLawError:
        return FrictionLawError(f"friction law {self.name}: {what}")

    def call(self, method: str, *args):
        """``law.method(*args)``; an exception inside it becomes a FrictionLawError naming the call."""
        shown = ", ".join([*(repr(a) for a in args if not isinstance(a, ContactContext)),
                           *("ctx" for a in args if isinstance(a, ContactContext))])
        try:
            return getattr(self.law, method)(*args)
        except Exception as e:  # noqa: BLE001 - a law's own bug, reported with its name
            raise self.fail(f"{method}({shown}) raised {type(e).__name__}: {e}") from e

    def names(self, attr: str, *, identifiers: bool, nonempty: bool) -> tuple[str, ...]:
        value = getattr(self.law, attr, None)
        if not isinstance(value, (tuple, list)) or not all(isinstance(v, str) and v for v in value):
            raise self.fail(f"{attr} = {_short(value)} must be a tuple of non-empty strings")
        if nonempty and not value:
            raise self.fail(f"{attr} = {_short(value)}: a law needs at least one mode of the closed contact "
                            f"(e.g. modes = ('slip',)); 'open' is added by the contact")
        if len(set(value)) != len(value):
            raise self.fail(f"{attr} = {_short(value)} has duplicates")
        if identifiers and not all(v.isidentifier() for v in value):
            raise self.fail(f"{attr} = {_short(value)}: each state name must be an identifier")
        return tuple(value)

    def context(self, states: tuple[str, ...]) -> ContactContext:
        params = self.call("parameters")
        if not isinstance(params, Mapping) or not all(isinstance(k, str) and isinstance(p, Param)
                                                      for k, p in params.items()):
            raise self.fail(f"parameters() returned {_short(params)}; expected a dict of field name to Param")
        return ContactContext(N=sp.Symbol("N", real=True), Ndot=sp.Symbol("Ndot", real=True),
                              v=sp.Symbol("v", real=True), f=sp.Symbol("f", real=True),
                              states={s: sp.Symbol(f"_state_{s}", real=True) for s in states},
                              params={k: p.symbol for k, p in params.items()})

    def state_map(self, value: Any, where: str, states: tuple[str, ...]) -> None:
        if not isinstance(value, Mapping):
            raise self.fail(f"{where} returned {_short(value)}; expected a dict of state name to expression")
        for k, v in value.items():
            if k not in states:
                raise self.fail(f"{where} names state {k!r}, which is not among its states {states}")
            if not _is_expr(v):
                raise self.fail(f"{where}[{k!r}] = {_short(v)}; expected a SymPy expression or a number")

    def held(self, rates: Mapping, where: str, discrete: tuple[str, ...]) -> None:
        """Refuse a rate of a discrete state that is not zero (such a state changes in resets only)."""
        for k in discrete:
            if k in rates and sp.sympify(rates[k]) != 0:
                raise self.fail(f"{where}[{k!r}] = {_short(rates[k])}, but {k!r} is among discrete_states, whose "
                                f"rate must be zero (resets alone set them)")

    def items(self, value: Any, where: str, what: str, nonempty: bool) -> list:
        """``value`` as a list, if it is an iterable of items (a list, tuple or generator)."""
        if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, Iterable):
            raise self.fail(f"{where} returned {_short(value)}; expected a {'non-empty ' * nonempty}list of {what}")
        out = list(value)
        if nonempty and not out:
            raise self.fail(f"{where} returned no {what}; expected at least one (the last unconditional)")
        return out

    def candidates(self, value: Any, where: str, modes: tuple[str, ...], states: tuple[str, ...]) -> None:
        value = self.items(value, where, "Candidate", nonempty=True)
        for i, c in enumerate(value):
            if not isinstance(c, Candidate):
                raise self.fail(f"{where}[{i}] = {_short(c)} is not a Candidate")
            if c.mode not in ("open", *modes):
                raise self.fail(f"{where}[{i}] names mode {c.mode!r}, which is not among its modes "
                                f"{('open', *modes)}")
            if not _is_condition(c.when):
                raise self.fail(f"{where}[{i}].when = {_short(c.when)}; expected a SymPy relational or True")
            self.state_map(c.reset, f"{where}[{i}].reset", states)

    def run(self) -> None:
        modes = self.names("modes", identifiers=False, nonempty=True)
        if "open" in modes:
            raise self.fail(f"modes = {modes} must not contain 'open' (the contact adds it)")
        states = self.names("states", identifiers=True, nonempty=False)
        discrete = self.names("discrete_states", identifiers=True, nonempty=False)
        if not set(discrete) <= set(states):
            raise self.fail(f"discrete_states = {discrete} names {sorted(set(discrete) - set(states))}, which are "
                            f"not among its states {states}")
        ctx = self.context(states)
        for mode in modes:
            force = self.call("force", mode, ctx)
            if not (isinstance(force, StickConstraint) or _is_expr(force)):
                raise self.fail(f"force({mode!r}, ctx) returned {_short(force)}; expected a SymPy expression, "
                                f"a number or STICK")
            rates = self.call("rates", mode, ctx)
            self.state_map(rates, f"rates({mode!r}, ctx)", states)
            self.held(rates, f"rates({mode!r}, ctx)", discrete)
            guards = self.items(self.call("guards", mode, ctx), f"guards({mode!r}, ctx)", "Guard", nonempty=False)
            for i, g in enumerate(guards):
                where = f"guards({mode!r}, ctx)[{i}]"
                if not isinstance(g, Guard):
                    raise self.fail(f"{where} = {_short(g)} is not a Guard")
                if not _is_expr(g.expr):
                    raise self.fail(f"{where}.expr = {_short(g.expr)}; expected a SymPy expression")
                if g.direction not in (-1, 0, 1) or isinstance(g.direction, bool):
                    raise self.fail(f"{where}.direction = {_short(g.direction)} must be -1, 0 or +1")
                self.candidates(g.candidates, f"{where}.candidates", modes, states)
        self.candidates(self.call("entry", ctx), "entry(ctx)", modes, states)
        self.state_map(self.call("exit_reset", ctx), "exit_reset(ctx)", states)
        open_rates = self.call("open_rates", ctx)
        self.state_map(open_rates, "open_rates(ctx)", states)
        self.held(open_rates, "open_rates(ctx)", discrete)
        energy = self.call("stored_energy", ctx)
        if not _is_expr(energy):
            raise self.fail(f"stored_energy(ctx) returned {_short(energy)}; expected a SymPy expression or a number")
        structure = self.call("structure")
        if not isinstance(structure, tuple):
            raise self.fail(f"structure() returned {_short(structure)}; expected a tuple")


def check_law(law: FrictionLaw) -> FrictionLaw:
    """Check a law instance against the interface: its modes, states and every method's output.

    Every method is called once per mode with a context of plain symbols, so a
    law is refused before equations are derived or code is generated. A law is
    checked once per class and :meth:`~FrictionLaw.structure`.

    Parameters
    ----------
    law : FrictionLaw

    Returns
    -------
    FrictionLaw
        ``law``, unchanged.

    Raises
    ------
    FrictionLawError
        Naming the law (``module:Class``), the method and the offending value: no
        closed mode, ``"open"`` among the modes, a state that is not an identifier,
        ``force`` returning ``None``, a candidate naming an unknown mode or state,
        a method that raises, ...
    """
    check_law_class(type(law))
    try:
        key = (type(law), repr(law.structure()))
    except Exception:  # noqa: BLE001 - reported by the full check below
        key = None
    if key is not None and key in _CHECKED:
        return law
    _Checker(law).run()
    if key is not None:
        _CHECKED.add(key)
    return law
