"""Friction laws from outside the package: import paths, entry points, the CLI, the docs' example."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from numpy.testing import assert_allclose

from blademodel.components import Contact, Coulomb, HarmonicForce, Iwan, Jenkins, Mass, Spring
from blademodel.components.friction import Candidate, ContactContext, FrictionLaw, Guard, registry
from blademodel.components.parameter import Number, as_param
from blademodel.config import ConfigError, load_config, load_model
from blademodel.zheng2022 import BladePair
from blademodel.model import Model
from blademodel.numeric import simulate
from blademodel.sweep.runner import points
from blademodel.sweep.spec import Study

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    tomllib = pytest.importorskip("tomli")

ROOT = Path(__file__).resolve().parents[1]
TESTS = Path(__file__).resolve().parent
EXAMPLES = ROOT / "docs" / "examples"


# --- a law that lives in this test file, outside the package ---------------------------
@dataclass(frozen=True)
class FileJenkins(FrictionLaw):
    """The bilinear (Jenkins) law again, written here against the public interface only."""

    mu: Number = 0.5
    kd: Number = 1e6
    _p: dict = field(init=False, repr=False, compare=False)

    modes = ("stick", "slip+", "slip-")
    states = ("z",)

    def __post_init__(self):
        object.__setattr__(self, "_p", {"mu": as_param(self.mu, "mu", field="friction: mu", minimum=0.0),
                                        "kd": as_param(self.kd, "kd", field="friction: kd", minimum=0.0,
                                                       strict=True)})

    def parameters(self):
        return dict(self._p)

    def force(self, mode, ctx: ContactContext):
        return ctx.params["kd"] * ctx.states["z"]

    def _slip_rate(self, s, ctx):
        return s * ctx.params["mu"] * ctx.Ndot / ctx.params["kd"]

    def rates(self, mode, ctx: ContactContext):
        return {"z": ctx.v if mode == "stick" else self._slip_rate(1 if mode == "slip+" else -1, ctx)}

    def guards(self, mode, ctx: ContactContext):
        mu, kd, N, z, v = ctx.params["mu"], ctx.params["kd"], ctx.N, ctx.states["z"], ctx.v
        if mode == "stick":
            return [Guard(mu * N - kd * z, -1, [Candidate("slip+")], "stick->slip+"),
                    Guard(mu * N + kd * z, -1, [Candidate("slip-")], "stick->slip-")]
        s = 1 if mode == "slip+" else -1
        return [Guard(s * (v - self._slip_rate(s, ctx)), -1, [Candidate("stick")], f"{mode}->stick")]

    def entry(self, ctx: ContactContext):
        return [Candidate("stick", sp.true, {"z": sp.Integer(0)})]

    def exit_reset(self, ctx: ContactContext):
        return {"z": sp.Integer(0)}

    def stored_energy(self, ctx: ContactContext):
        return ctx.params["kd"] * ctx.states["z"] ** 2 / 2


COMPONENTS = (ROOT / "models" / "blade_pair_components.yaml").read_text()
FRICTION = "friction: {law: coulomb, mu: mu}"
assert FRICTION in COMPONENTS


def components_yaml(tmp_path: Path, friction: str, name: str = "model.yaml") -> Path:
    text = COMPONENTS.replace(FRICTION, friction).replace("parameters:\n", "parameters:\n  kd: 1e6\n")
    path = tmp_path / name
    path.write_text(text)
    return path


def cli(args, pythonpath) -> dict:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(map(str, pythonpath)))
    out = subprocess.run([sys.executable, "-m", "blademodel", *map(str, args)], env=env, capture_output=True,
                         text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


RUN = ["--transient", "20", "--periods", "20", "--json"]


@pytest.mark.slow   # ~35 s in CI; test_entry_point_law_through_the_cli takes an external law through the CLI
def test_law_from_this_file_through_yaml_and_the_cli(tmp_path):
    """``law: test_external_law:FileJenkins`` in a components YAML, simulated by the CLI in a
    fresh process, gives exactly the built-in bilinear law's motion."""
    path = components_yaml(tmp_path, 'friction: {law: "test_external_law:FileJenkins", mu: mu, kd: kd}')
    rep = cli(["simulate", path, *RUN], [TESTS])
    assert rep["status"] == "done"
    ref_model = load_model(components_yaml(tmp_path, "friction: {law: bilinear, mu: mu, kd: kd}", "ref.yaml"))
    assert isinstance(ref_model.contacts[0].friction, Jenkins)
    ref = simulate(ref_model, periods=20, transient=20, steps_per_period=1000)
    assert ref.counters["events"] >= 100
    assert rep["counters"]["events"] == ref.counters["events"]
    final = np.array([rep["final_state"][k] for k in ref.state_names])
    assert_allclose(final, ref.final_state, rtol=0, atol=1e-12 * np.max(np.abs(ref.final_state)))
    # and in this process, by the same path
    law = load_model(path).contacts[0].friction
    assert type(law).__name__ == "FileJenkins" and law.parameters()["kd"].name == "kd"


# --- entry points ------------------------------------------------------------------------
def fake_distribution(root: Path, entries: dict[str, str]) -> Path:
    """A minimal installed distribution on ``root`` registering ``entries`` as friction laws."""
    info = root / "fakelaws-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: fakelaws\nVersion: 0.1\n")
    lines = [f"{k} = {v}" for k, v in entries.items()]
    (info / "entry_points.txt").write_text(f"[{registry.ENTRY_POINT_GROUP}]\n" + "\n".join(lines) + "\n")
    return root


@pytest.fixture
def registered(tmp_path, monkeypatch):
    """``filejenkins`` registered by an entry point of a fake installed package."""
    root = fake_distribution(tmp_path / "site", {"filejenkins": "test_external_law:FileJenkins"})
    monkeypatch.syspath_prepend(str(root))
    registry.refresh()
    yield root
    monkeypatch.undo()
    registry.refresh()


def test_entry_point_law_by_name(registered):
    assert registry.known_names() == ["bilinear", "coulomb", "filejenkins", "iwan", "none"]
    assert registry.registered_laws()["filejenkins"] == "test_external_law:FileJenkins"
    assert registry.law_class("filejenkins") is FileJenkins
    law = BladePair(friction="filejenkins").friction_law()
    assert isinstance(law, FileJenkins) and law.parameters()["mu"].name == "mu"   # the pair's mu and kd
    study = Study(name="s", laws=["bilinear", "filejenkins"], sweep={"gamma": {"values": [1.0, 2.0]}})
    assert points(study)[2] == ["bilinear", "bilinear", "filejenkins", "filejenkins"]


def test_entry_point_cannot_take_a_builtin_name(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(fake_distribution(tmp_path, {"coulomb": "test_external_law:FileJenkins"})))
    registry.refresh()
    try:
        with pytest.warns(UserWarning, match="'coulomb' is a built-in friction law"):
            assert registry.law_class("coulomb") is Coulomb
    finally:
        monkeypatch.undo()
        registry.refresh()


def test_entry_point_law_through_the_cli(registered, tmp_path):
    (tmp_path / "pair.yaml").write_text("model: blade_pair\nfriction: filejenkins\ngamma: 8\n")
    rep = cli(["simulate", tmp_path / "pair.yaml", *RUN], [registered, TESTS])
    ref = simulate(BladePair(friction="bilinear", gamma=8).build(), periods=20, transient=20, steps_per_period=1000)
    assert rep["counters"]["events"] == ref.counters["events"] >= 100
    final = np.array([rep["final_state"][k] for k in ref.state_names])
    assert_allclose(final, ref.final_state, rtol=0, atol=1e-12 * np.max(np.abs(ref.final_state)))


def test_builtin_laws_are_registered_in_pyproject():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert meta["project"]["entry-points"][registry.ENTRY_POINT_GROUP] == registry.BUILTIN
    for name, path in registry.BUILTIN.items():
        assert f"{registry.law_class(name).__module__}:{registry.law_class(name).__qualname__}" == path


# --- names, options and their errors ------------------------------------------------------
def test_unknown_law_names_list_the_known_ones(tmp_path):
    known = "known laws are bilinear, coulomb, iwan, none"
    with pytest.raises(ValueError, match=known):
        registry.law_class("iwann")
    (tmp_path / "p.yaml").write_text("model: blade_pair\nfriction: iwann\n")
    with pytest.raises(ConfigError, match=f"p.yaml:2: friction = 'iwann': unknown friction law 'iwann': {known}"):
        load_config(tmp_path / "p.yaml")
    with pytest.raises(ValueError, match=known):
        Study(name="s", laws=["coulomb", "iwann"], sweep={"gamma": {"values": [1.0]}})
    path = components_yaml(tmp_path, "friction: {law: iwann}")
    with pytest.raises(ConfigError, match=f"contacts.0.friction.law = 'iwann': unknown friction law 'iwann': {known}"):
        load_config(path)


def test_builtin_names_keep_their_laws():
    assert type(BladePair(friction="coulomb").friction_law()) is Coulomb
    assert type(BladePair(friction="bilinear").friction_law()) is Jenkins
    assert BladePair(friction="none").friction_law().modes == ("closed",)
    band = BladePair(friction="coulomb", stick="band", stick_velocity_tol=2e-4).friction_law()
    assert band.parameters()["stick_velocity_tol"].value == 2e-4


@pytest.mark.parametrize("options, needle", [
    ("{elements: 0}", "p.yaml:3: friction_options.elements = 0: iwan: elements = 0 must be an integer >= 1"),
    ("{elements: 3, bogus: 1}", "p.yaml:3: friction_options.bogus = 1: iwan: unknown option of Iwan (known: mu, kd,"),
    ("{distribution: gauss}", "friction_options.distribution = 'gauss': iwan: distribution = 'gauss' must be one of"),
    ("{mu: 0.3}", "friction_options.mu = 0.3: 'mu' is a field of the pair; set it there"),
])
def test_friction_options_errors_name_the_field(tmp_path, options, needle):
    (tmp_path / "p.yaml").write_text(f"model: blade_pair\nfriction: iwan\nfriction_options: {options}\n")
    with pytest.raises(ConfigError) as e:
        load_config(tmp_path / "p.yaml")
    assert needle in str(e.value), str(e.value)


def test_friction_options_reach_the_law(tmp_path):
    (tmp_path / "p.yaml").write_text("model: blade_pair\nfriction: iwan\nkd: 2e6\n"
                                     "friction_options: {elements: 5, distribution: uniform}\n")
    law = load_model(tmp_path / "p.yaml").contacts[0].friction
    assert isinstance(law, Iwan) and law.elements == 5 and law.parameters()["kd"].value == 2e6
    path = components_yaml(tmp_path, "friction: {law: iwan, mu: mu, kd: kd, elements: 3}")
    law = load_model(path).contacts[0].friction
    assert isinstance(law, Iwan) and law.elements == 3 and law.parameters()["mu"].name == "mu"
    path = components_yaml(tmp_path, "friction: {law: iwan, elements: -1}")
    with pytest.raises(ConfigError, match="contacts.0.friction.elements = -1: iwan: elements = -1 must be"):
        load_config(path)


def test_study_law_options():
    study = Study(name="s", base={"model": "blade_pair"}, laws=["coulomb", "iwan"],
                  law_options={"iwan": {"elements": 6}}, sweep={"gamma": {"values": [1.0]}})
    _, _, laws, overrides = points(study)
    assert laws == ["coulomb", "iwan"]
    assert overrides[0] == {"gamma": 1.0, "friction": "coulomb"}
    assert overrides[1] == {"gamma": 1.0, "friction": "iwan", "friction_options": {"elements": 6}}
    with pytest.raises(ValueError, match="law_options names 'bilinear', which is not among laws"):
        Study(name="s", laws=["iwan"], law_options={"bilinear": {}}, sweep={"gamma": {"values": [1.0]}})


# --- the worked example of docs/friction_laws.md -----------------------------------------
@pytest.fixture
def static_kinetic(monkeypatch):
    monkeypatch.syspath_prepend(str(EXAMPLES))
    from static_kinetic import StaticKineticCoulomb
    return StaticKineticCoulomb


@pytest.mark.slow   # a cold compile (~50 s in CI); test_entry_point_law_through_the_cli runs an external law
def test_docs_law_with_equal_coefficients_is_coulomb(static_kinetic):
    law = "static_kinetic:StaticKineticCoulomb"
    cfg = BladePair(friction=law, friction_options={"mu_s": 0.5, "mu_k": 0.5})
    assert isinstance(cfg.friction_law(), static_kinetic)
    r = simulate(cfg.build(), periods=30, steps_per_period=1000)
    ref = simulate(BladePair(friction="coulomb").build(), periods=30, steps_per_period=1000)
    assert r.counters["events"] == ref.counters["events"] >= 100
    assert_allclose(r.final_state, ref.final_state, rtol=0, atol=1e-12 * np.max(np.abs(ref.final_state)))
    with pytest.raises(ValueError, match="mu_k = 0.6 must not exceed mu_s = 0.5"):
        static_kinetic(mu_s=0.5, mu_k=0.6)


@pytest.mark.slow   # a cold compile (~20 s in CI); the docs law's Coulomb limit runs by default
def test_docs_law_breaks_away_at_the_static_limit(static_kinetic):
    # A mass on a spring, pressed on the ground with the constant load N and driven
    # harmonically: while it sticks, f = P sin(w t) - k x; it breaks away when |f| = mu_s N.
    m, k, P, omega, kc = 1.0, 1e4, 10.0, 20.0, 1e5
    mu_s, mu_k, N = 0.75, 0.5, 4.0
    mass = Mass("1", m, dofs=("x",))
    model = Model((mass,), (Spring("x1", k),), (), (HarmonicForce(mass, P, omega),),
                  (Contact(mass, None, gap=-N / kc, alpha=0.0, k=kc, friction=static_kinetic(mu_s, mu_k)),))
    r = simulate(model, periods=6, transient=2, steps_per_period=2000)
    ev = [(t, g) for t, g in zip(r.events["t"], r.events["guard"])]
    breakaways = [t for t, g in ev if g.startswith("c: stick->slip")]
    assert len(breakaways) >= 10
    for t_b in breakaways:
        sticking = (r.t < t_b) & (r.mode == r.mode_names.index("stick"))
        x_s = r.y[np.flatnonzero(sticking)[-1], r.index("x1")]     # x is frozen while sticking
        f_s = P * math.sin(omega * t_b) - k * x_s
        assert abs(abs(f_s) - mu_s * N) <= 1e-8 * mu_s * N
