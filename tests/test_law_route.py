"""One route for every friction law: built-in and external laws named, parameterised per contact and
validated alike, in the components YAML format and in a bladed disk's per-contact laws."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
import yaml

from blademodel.components import Contact, Damper, HarmonicForce, Iwan, Jenkins, Mass, Param, Spring
from blademodel.components.friction import Candidate, ContactContext, FrictionLaw, registry
from blademodel.components.parameter import Number, as_param
from blademodel.config import BladedDisk, ConfigError, apply_overrides, load_config, load_model
from blademodel.model import Model
from blademodel.numeric import simulate

ROOT = Path(__file__).resolve().parents[1]
ROW = (ROOT / "models" / "blade_row_3.yaml").read_text()
FRICTION = ("friction: {law: coulomb, mu: mu}", "friction: {law: bilinear, mu: mu, kd: kd}")
assert all(f in ROW for f in FRICTION)
LAW = "test_law_route:Regularised"


# --- an external law, defined here -----------------------------------------------------------
@dataclass(frozen=True)
class Regularised(FrictionLaw):
    """Coulomb friction smoothed over the velocity ``v0``: ``f = mu N tanh(v / v0)``, one closed mode."""

    mu: Number = 0.5
    v0: Number = 0.05
    _p: dict = field(init=False, repr=False, compare=False)

    modes = ("closed",)

    def __post_init__(self):
        object.__setattr__(self, "_p", {"mu": as_param(self.mu, "mu", field="friction: mu", minimum=0.0),
                                        "v0": as_param(self.v0, "v0", field="friction: v0", minimum=0.0,
                                                       strict=True)})

    def parameters(self):
        return dict(self._p)

    def force(self, mode, ctx: ContactContext):
        return ctx.params["mu"] * ctx.N * sp.tanh(ctx.v / ctx.params["v0"])

    def guards(self, mode, ctx: ContactContext):
        return []

    def entry(self, ctx: ContactContext):
        return [Candidate("closed")]


# --- the blade row of models/blade_row_3.yaml, from YAML and in Python -----------------------
def row_yaml(tmp_path: Path, first: str, second: str, name: str = "row.yaml") -> Path:
    """``models/blade_row_3.yaml`` with the friction blocks of its contacts c12 and c23 replaced."""
    path = tmp_path / name
    path.write_text(ROW.replace(FRICTION[0], f"friction: {first}").replace(FRICTION[1], f"friction: {second}"))
    return path


def row_python(first: FrictionLaw, second: FrictionLaw) -> Model:
    """The same row written in Python: the parameters of ``parameters:`` as Params, the given laws."""
    P = {k: Param(k, float(v)) for k, v in yaml.safe_load(ROW)["parameters"].items()}
    masses = [Mass(str(i), P["m"]) for i in (1, 2, 3)]
    springs = [Spring(f"{d}{i}", P[f"k{d}"]) for i in (1, 2, 3) for d in "xy"]
    dampers = [Damper(f"{d}{i}", P[f"c{d}"]) for i in (1, 2, 3) for d in "xy"]
    forces = [HarmonicForce(m, P["F0"], P["omega"], P[f"phi{m.name}"], P["beta"]) for m in masses]
    contacts = [Contact(masses[i], masses[i + 1], gap=P["Delta"], alpha=P["alpha"], k=P["k"], friction=law,
                        name=name) for i, (name, law) in enumerate((("c12", first), ("c23", second)))]
    return Model(tuple(masses), tuple(springs), tuple(dampers), tuple(forces), tuple(contacts), name="blade_row_3")


def run(model: Model):
    return simulate(model, periods=10, transient=10, steps_per_period=1000)


def friction_values(model: Model) -> dict[str, float]:
    return {k: v for k, v in model.parameters.items() if any(k.endswith(f"_{c}") for c in ("c12", "c23"))}


@pytest.mark.parametrize("first, second, laws, values", [
    pytest.param("{law: iwan, mu: 0.5, elements: 2}", "{law: iwan, mu: 0.3, elements: 2}",
                 lambda n: Iwan(mu=Param(f"mu_{n}", 0.5 if n == "c12" else 0.3), kd=Param(f"kd_{n}", 1e6),
                                elements=2),
                 {"mu_c12": 0.5, "kd_c12": 1e6, "mu_c23": 0.3, "kd_c23": 1e6}, marks=pytest.mark.slow),
    pytest.param(f'{{law: "{LAW}", mu: 0.5, v0: 0.05}}', f'{{law: "{LAW}", mu: 0.3}}',
                 lambda n: Regularised(mu=Param(f"mu_{n}", 0.5 if n == "c12" else 0.3), v0=Param(f"v0_{n}", 0.05)),
                 {"mu_c12": 0.5, "v0_c12": 0.05, "mu_c23": 0.3, "v0_c23": 0.05}, marks=pytest.mark.slow),
], ids=["iwan", "external"])   # both slow: a cold compile each (~40 s in CI); the other tests here route laws
def test_two_contacts_with_their_own_values_are_the_python_model(tmp_path, first, second, laws, values):
    """Plain numbers (and defaults) of each contact's law get that contact's symbols, as a Python model
    would name them; the YAML model is then the Python model, to the last bit of its motion."""
    model = load_model(row_yaml(tmp_path, first, second))
    reference = row_python(laws("c12"), laws("c23"))
    assert friction_values(model) == values == friction_values(reference)
    assert model.structure_key() == reference.structure_key()
    a, b = run(model), run(reference)
    assert a.counters["events"] == b.counters["events"]
    assert {g.split(":")[0] for g in a.events["guard"]} >= {"c12", "c23"}    # both contacts close
    np.testing.assert_array_equal(a.final_state, b.final_state)
    # the per-contact values act: the row with mu = 0.5 at both contacts moves otherwise
    same = load_model(row_yaml(tmp_path, first, second.replace("mu: 0.3", "mu: 0.5"), "same.yaml"))
    assert np.max(np.abs(run(same).final_state - a.final_state)) > 1e-3 * np.max(np.abs(a.final_state))


def test_two_bilinear_contacts_keep_their_symbols(tmp_path):
    """The bilinear law took a route of its own before; its symbols (hence its kernel) are unchanged."""
    model = load_model(row_yaml(tmp_path, "{law: bilinear, mu: 0.5}", "{law: bilinear, mu: 0.3, kd: kd}"))
    reference = row_python(Jenkins(mu=Param("mu_c12", 0.5), kd=Param("kd_c12", 1e6)),
                           Jenkins(mu=Param("mu_c23", 0.3), kd=Param("kd", 1e6)))
    assert model.structure() == reference.structure()
    assert model.parameters == reference.parameters


def test_a_named_parameter_is_shared(tmp_path):
    model = load_model(row_yaml(tmp_path, "{law: iwan, mu: mu, elements: 2}", "{law: iwan, mu: mu, kd: kd}"))
    laws = [c.friction for c in model.contacts]
    assert [law.parameters()["mu"].name for law in laws] == ["mu", "mu"]
    assert [law.parameters()["kd"].name for law in laws] == ["kd_c12", "kd"]
    model = load_model(row_yaml(tmp_path, "{law: coulomb, mu: mu}", f'{{law: "{LAW}", v0: cx}}'))
    assert model.contacts[1].friction.parameters() == {"mu": Param("mu_c23", 0.5), "v0": Param("cx", 3.5)}


def test_defaults_can_be_set_from_outside(tmp_path):
    """A law's numeric defaults are part of the config, so ``--set`` reaches them by their key."""
    config = load_config(row_yaml(tmp_path, "iwan", "{law: iwan, elements: 2}"))
    assert config.model_dump()["contacts"][0]["friction"] == {"law": "iwan", "mu": 0.5, "kd": 1e6, "elements": 4}
    assert type(config).model_validate(config.model_dump()).model_dump() == config.model_dump()
    out = apply_overrides(config, {"contacts.0.friction.mu": "0.4"})
    assert friction_values(out.build()) == {"mu_c12": 0.4, "kd_c12": 1e6, "mu_c23": 0.5, "kd_c23": 1e6}
    assert friction_values(config.build()) == {"mu_c12": 0.5, "kd_c12": 1e6, "mu_c23": 0.5, "kd_c23": 1e6}


@pytest.fixture
def registered(tmp_path, monkeypatch):
    """``regularised`` registered by the entry point of a throw-away installed distribution."""
    info = tmp_path / "site" / "routelaws-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: routelaws\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[{registry.ENTRY_POINT_GROUP}]\nregularised = {LAW}\n")
    monkeypatch.syspath_prepend(str(tmp_path / "site"))
    registry.refresh()
    yield
    monkeypatch.undo()
    registry.refresh()


def test_a_law_by_entry_point_name_takes_the_same_route(tmp_path, registered):
    by_name = load_model(row_yaml(tmp_path, "{law: regularised, mu: 0.5}", "{law: regularised, mu: 0.3}"))
    by_path = load_model(row_yaml(tmp_path, f'{{law: "{LAW}", mu: 0.5}}', f'{{law: "{LAW}", mu: 0.3}}', "p.yaml"))
    assert friction_values(by_name) == {"mu_c12": 0.5, "v0_c12": 0.05, "mu_c23": 0.3, "v0_c23": 0.05}
    assert by_name.structure_key() == by_path.structure_key()
    with pytest.raises(ConfigError, match="contacts.1.friction.v0 = -1: regularised: v0 = -1.0 must be > 0.0"):
        load_config(row_yaml(tmp_path, "{law: regularised}", "{law: regularised, v0: -1}"))


# --- errors in YAML terms ----------------------------------------------------------------------
@pytest.mark.parametrize("second, expected", [
    ("{law: iwan, elements: 0}", "contacts.1.friction.elements = 0: iwan: elements = 0 must be an integer >= 1"),
    ("{law: iwan, distribution: gauss}",
     "contacts.1.friction.distribution = 'gauss': iwan: distribution = 'gauss' must be one of uniform, custom"),
    ("{law: iwan, bogus: 1}", "contacts.1.friction.bogus = 1: iwan: unknown option of Iwan (known: mu, kd, "),
    ("{law: bilinear, mu: -1}", "contacts.1.friction.mu = -1: bilinear: mu = -1.0 must be >= 0.0"),
    ("{law: iwan, mu: yes}", "contacts.1.friction.mu = True: iwan: mu = True must be a number, not a boolean"),
    ("{law: iwan, mu: 1e400}", "contacts.1.friction.mu = '1e400': Input should be a finite number"),
    ("{law: iwan, mu: mu_typo}", "contacts.1.friction.mu = 'mu_typo': unknown parameter (known: m, kx, ky,"),
    (f'{{law: "{LAW}", v0: 0}}', f"contacts.1.friction.v0 = 0: {LAW}: v0 = 0.0 must be > 0.0"),
    (f'{{law: "{LAW}", kd: 1e6}}', f"contacts.1.friction.kd = 1000000.0: {LAW}: unknown option of Regularised"),
])
def test_a_bad_option_is_named_by_its_field_and_value(tmp_path, second, expected):
    path = row_yaml(tmp_path, "{law: coulomb, mu: mu}", second)
    with pytest.raises(ConfigError) as e:
        load_config(path)
    line = ROW.splitlines().index("    " + FRICTION[1]) + 1
    assert f"row.yaml:{line}: {expected}" in str(e.value), str(e.value)
    assert "Param(" not in str(e.value)


def test_a_declared_parameter_the_law_refuses_is_named_where_it_is_declared(tmp_path):
    path = row_yaml(tmp_path, "{law: coulomb, mu: mu}", "{law: iwan, kd: kd}")
    path.write_text(path.read_text().replace("  kd: 1e6 ", "  kd: -1e6 "))
    with pytest.raises(ConfigError) as e:
        load_config(path)
    line = ROW.splitlines().index(next(s for s in ROW.splitlines() if s.startswith("  kd: 1e6"))) + 1
    assert (f"row.yaml:{line}: parameters.kd = -1000000.0: iwan: kd = -1000000.0 must be > 0.0 "
            f"(used by contacts.1.friction.kd)") in str(e.value), str(e.value)


def test_text_that_names_a_parameter_stays_text_for_an_option_that_is_none(tmp_path):
    """``distribution: m`` is the text 'm' to Iwan, although ``m`` is a declared parameter."""
    path = row_yaml(tmp_path, "{law: coulomb, mu: mu}", "{law: iwan, distribution: m}")
    with pytest.raises(ConfigError, match="contacts.1.friction.distribution = 'm': iwan: distribution = 'm' must be"):
        load_config(path)


def test_a_symbol_standing_for_two_values_names_both_fields(tmp_path):
    path = row_yaml(tmp_path, "{law: coulomb, mu: mu}", "{law: iwan, mu: 0.3}")
    path.write_text(path.read_text().replace("  kd: 1e6 ", "  kd: 1e6 \n  mu_c23: 0.2\n")
                    .replace("{a: x1, c: cx}", "{a: x1, c: mu_c23}"))
    with pytest.raises(ConfigError) as e:
        load_config(path)
    assert ("contacts.1.friction.mu = 0.3: its symbol mu_c23 already stands for 0.2 at dampers.0.c; declare the "
            "values under 'parameters:' and write their names in these fields") in str(e.value), str(e.value)


# --- a bladed disk's per-contact laws ---------------------------------------------------------
def test_disk_contacts_with_their_own_options_get_their_own_symbols():
    disk = BladedDisk(blades=3, friction=LAW, friction_options={"v0": 0.05},
                      contacts={0: {"friction_options": {"v0": 0.02}}, 2: {"friction_options": {"v0": 0.03}}})
    params = disk.build().parameters
    assert {k: params[k] for k in ("v0", "v0_c1", "v0_c3", "mu")} == {"v0": 0.05, "v0_c1": 0.02, "v0_c3": 0.03,
                                                                     "mu": 0.5}
    # a contact with the disk's law and options shares the disk's symbols, as before
    assert "v0_c2" not in params and "mu_c1" not in params
    iwan = BladedDisk(blades=3, friction="iwan", contacts={1: {"mu": 0.3, "friction_options": {"elements": 2}}})
    assert {k: v for k, v in iwan.build().parameters.items() if k[:2] in ("mu", "kd")} == {
        "mu": 0.5, "kd": 1e6, "mu_c2": 0.3}


@pytest.mark.parametrize("options, expected", [
    ("{v0: -1}", "contacts.1.friction_options.v0 = -1: {law}: v0 = -1.0 must be > 0.0"),
    ("{v0: yes}", "contacts.1.friction_options.v0 = True: {law}: v0 = True must be a number, not a boolean"),
])
def test_disk_option_errors_name_the_contact_field(tmp_path, options, expected):
    (tmp_path / "d.yaml").write_text(f"model: bladed_disk\nblades: 3\nfriction: {LAW}\n"
                                     f"contacts:\n  1: {{friction_options: {options}}}\n")
    with pytest.raises(ConfigError) as e:
        load_config(tmp_path / "d.yaml")
    assert f"d.yaml:5: {expected.format(law=LAW)}" in str(e.value), str(e.value)
