"""Config formats and loading: validation errors point at file, line, field and value;
the component format builds the same model as the paper's blade pair."""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import pytest
import sympy as sp
import yaml

from blademodel.components import Coulomb, Jenkins
from blademodel.config import ComponentsModel, ConfigError, apply_overrides, load_config, load_model
from blademodel.zheng2022 import BladePair
from blademodel.model import Model
from blademodel.symbolic import derive

MODELS = Path(__file__).resolve().parents[1] / "models"


def write(tmp_path, text, name="m.yaml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text).lstrip("\n"))
    return path


def error(tmp_path, text) -> str:
    path = write(tmp_path, text)
    with pytest.raises(ConfigError) as info:
        load_config(path)
    msg = str(info.value)
    assert str(path) in msg
    return msg


def first_line_of(msg: str, needle: str) -> str:
    return next(line for line in msg.splitlines() if needle in line)


# A valid component model; tests break one line of it at a time.
GOOD = """
model: components
name: two
parameters:
  kx: 1e5
  omega: 290
masses:
  - name: 1
    m: 0.085
  - {name: 2, m: 0.085, dofs: [x]}
springs:
  - {a: x1, k: kx}
  - {a: x2, b: x1, k: 2e4}
dampers:
  - {a: y1, c: 3.5}
forces:
  - {mass: 1, amplitude: 60, omega: omega}
contacts:
  - name: c
    bodies: [1, 2]
    gap: 4e-5
    alpha: 1.0
    k: 4e5
    friction: {law: coulomb, mu: 0.5}
"""


def test_good_components_model_builds(tmp_path):
    config = load_config(write(tmp_path, GOOD))
    assert isinstance(config, ComponentsModel)
    model = load_model(write(tmp_path, GOOD))
    assert isinstance(model, Model)
    assert model.coordinates == ("x1", "y1", "x2")
    assert model.parameters["kx"] == 1e5            # '1e5' is a string to PyYAML
    assert model.parameters["k_x2_x1"] == 2e4
    assert model.parameters["mu_c"] == 0.5          # per-contact default symbol
    assert model.parameters["omega"] == 290.0


# --- validation errors: field, value and line ----------------------------------------------
@pytest.mark.parametrize("old, new, expected", [
    ("    m: 0.085\n", "    m: -1.0\n", "m.yaml:8: masses.0.m = -1.0: Input should be greater than 0"),
    ("    m: 0.085\n", "    m: .nan\n", "m.yaml:8: masses.0.m = nan: Input should be a finite number"),
    ("    m: 0.085\n", "    m: .inf\n", "m.yaml:8: masses.0.m = inf: Input should be a finite number"),
    ("    m: 0.085\n", "    m: 'nan'\n", "m.yaml:8: masses.0.m = 'nan': Input should be a finite number"),
    ("    m: 0.085\n", "    m: 1.2.3\n",
     "m.yaml:8: masses.0.m = '1.2.3': Input should be a number or the name of a parameter"),
    ("    m: 0.085\n", "    m: mass\n", "m.yaml:8: masses.0.m = 'mass': unknown parameter (known: kx, omega)"),
    ("  - {a: x1, k: kx}", "  - {a: x1, k: -3}",
     "m.yaml:11: springs.0.k = -3: Input should be greater than or equal to 0"),
    ("  - {a: x1, k: kx}", "  - {a: x3, k: kx}", "m.yaml:11: springs.0.a = 'x3': unknown coordinate"),
    ("  - {a: x2, b: x1, k: 2e4}", "  - {a: x2, b: y2, k: 2e4}",
     "m.yaml:12: springs.1.b = 'y2': unknown coordinate (known: x1, y1, x2)"),
    ("  - {a: y1, c: 3.5}", "  - {a: z1, c: 3.5}", "m.yaml:14: dampers.0.a = 'z1': unknown coordinate"),
    ("  - {mass: 1, amplitude: 60", "  - {mass: 3, amplitude: 60", "m.yaml:16: forces.0.mass = '3': unknown mass"),
    ("omega: omega}", "omega: 0}", "m.yaml:16: forces.0.omega = 0: Input should be greater than 0"),
    ("    bodies: [1, 2]", "    bodies: [1, 5]", "m.yaml:19: contacts.0.bodies.1 = '5': unknown body"),
    ("    bodies: [1, 2]", "    bodies: [1, 1]", "m.yaml:19: contacts.0.bodies.1 = '1': a body cannot touch itself"),
    ("{law: coulomb, mu: 0.5}", "{law: magic, mu: 0.5}",
     "m.yaml:23: contacts.0.friction.law = 'magic': unknown friction law 'magic'"),
    ("{law: coulomb, mu: 0.5}", "{law: coulomb, mu: -0.5}",
     "m.yaml:23: contacts.0.friction.mu = -0.5: coulomb: mu = -0.5 must be >= 0.0"),
    ("{law: coulomb, mu: 0.5}", "{law: coulomb, kd: 1e6}",
     "m.yaml:23: contacts.0.friction.kd = 1000000.0: coulomb: unknown option of Coulomb (known: mu, "
     "stick_velocity_tol)"),
    ("    alpha: 1.0\n", "    alpha: 1.0\n    angle: 2\n",
     "m.yaml:22: contacts.0.angle = 2: Extra inputs are not permitted"),
    ("  - {name: 2, m: 0.085, dofs: [x]}", "  - {name: 2, m: 0.085, dofs: [x, z]}",
     "m.yaml:9: masses.1.dofs.1 = 'z': Input should be 'x' or 'y'"),
    ("  - {name: 2, m: 0.085, dofs: [x]}", "  - {name: 1, m: 0.085, dofs: [x]}",
     "m.yaml:9: masses.1.name = '1': duplicate mass name"),
    ("  kx: 1e5", "  kx: -1e5",
     "m.yaml:4: parameters.kx = -100000.0: Input should be greater than or equal to 0 (used by springs.0.k)"),
])
def test_components_errors_name_line_field_value(tmp_path, old, new, expected):
    assert old in GOOD
    msg = error(tmp_path, GOOD.replace(old, new, 1))
    assert expected in msg, msg


def test_missing_field_names_it_with_its_line(tmp_path):
    msg = error(tmp_path, GOOD.replace("    gap: 4e-5\n", ""))
    assert "m.yaml:18: contacts.0.gap: Field required" in msg, msg


BLADE = """
model: blade_pair
m: 0.085
kx: 1e5
ky: 3e6
friction: coulomb
blade2:
  m: 0.09
  kx: 1.1e5
"""


@pytest.mark.parametrize("old, new, expected", [
    ("m: 0.085", "m: -1.0", "m.yaml:2: m = -1.0: Input should be greater than 0"),
    ("m: 0.085", "m: .nan", "m.yaml:2: m = nan: Input should be a finite number"),
    ("kx: 1e5", "kx: -.inf", "m.yaml:3: kx = -inf: Input should be a finite number"),
    ("kx: 1e5", "kx: abc", "m.yaml:3: kx = 'abc': Input should be a valid number"),
    ("friction: coulomb", "friction: magic",
     "m.yaml:5: friction = 'magic': unknown friction law 'magic': known laws are bilinear, coulomb, iwan, none"),
    ("friction: coulomb", "friction: coulomb\ngama: 4", "m.yaml:6: gama = 4: Extra inputs are not permitted"),
    ("  m: 0.09", "  m: -0.09", "m.yaml:7: blade2.m = -0.09: Input should be greater than 0"),
    ("  kx: 1.1e5", "  kxx: 1.1e5", "m.yaml:8: blade2.kxx = '1.1e5': Extra inputs are not permitted"),
])
def test_blade_pair_errors_name_line_field_value(tmp_path, old, new, expected):
    assert old in BLADE
    msg = error(tmp_path, BLADE.replace(old, new, 1))
    assert expected in msg, msg


def test_exponent_strings_are_numbers(tmp_path):
    assert yaml.safe_load("kx: 1e5")["kx"] == "1e5"   # the PyYAML quirk this guards against
    config = load_config(write(tmp_path, BLADE))
    assert config.kx == 1e5 and config.ky == 3e6 and config.blade2.kx == 1.1e5


@pytest.mark.parametrize("text, line, needle", [
    ("model: blade_pair\nm: 1\nkx: a: b\n", 3, "mapping values are not allowed here"),
    ("model: blade_pair\nm: 1\nkx: [1, 2\nky: 3\n", 4, "expected ',' or ']'"),
    ("model: blade_pair\nm: 0.085\n  kx: 3\n", 3, "mapping values are not allowed here"),
])
def test_yaml_syntax_error_gives_file_and_line(tmp_path, text, line, needle):
    msg = error(tmp_path, text)
    assert f"m.yaml:{line}: YAML syntax error" in msg, msg
    assert needle in msg


def test_duplicate_key_is_an_error(tmp_path):
    msg = error(tmp_path, "model: blade_pair\nm: 1\ngap: 1e-5\nm: 2\n")
    assert "m.yaml:4: duplicate key 'm'" in msg


def test_model_key_is_required_and_checked(tmp_path):
    msg = error(tmp_path, "m: 1\n")
    assert "model: missing key: expected one of 'components', 'bladed_disk', 'blade_pair'" in msg
    msg = error(tmp_path, "m: 1\nmodel: blade_pairs\n")
    assert "m.yaml:2: model = 'blade_pairs': expected one of" in msg


def test_top_level_must_be_a_mapping(tmp_path):
    assert "expected a mapping" in error(tmp_path, "- 1\n- 2\n")


def test_missing_file_is_a_config_error(tmp_path):
    with pytest.raises(ConfigError, match="cannot read"):
        load_config(tmp_path / "nope.yaml")


def test_config_error_is_a_value_error_with_line(tmp_path):
    path = write(tmp_path, GOOD.replace("    m: 0.085\n", "    m: 0\n"))
    with pytest.raises(ValueError) as info:
        load_config(path)
    assert isinstance(info.value, ConfigError)
    assert info.value.line == 8 and info.value.path == str(path)


def test_symbol_conflict_names_both_fields(tmp_path):
    text = """
    model: components
    parameters: {m_1: 2}
    masses:
      - {name: 1, m: 1}
      - {name: 2, m: m_1}
    """
    msg = error(tmp_path, text)
    assert ("m.yaml:5: masses.1.m = 2.0: its symbol m_1 already stands for 1.0 at masses.0.m; declare the values "
            "under 'parameters:' and write their names in these fields") in msg, msg


# --- friction laws ---------------------------------------------------------------------
def test_friction_shorthand_and_default(tmp_path):
    text = GOOD.replace("{law: coulomb, mu: 0.5}", "bilinear")
    model = load_model(write(tmp_path, text))
    assert isinstance(model.contacts[0].friction, Jenkins)
    text = GOOD.replace("    friction: {law: coulomb, mu: 0.5}\n", "")
    assert load_model(write(tmp_path, text)).contacts[0].modes == ("open", "closed")


def test_external_friction_law_by_import_path(tmp_path):
    text = GOOD.replace("{law: coulomb, mu: 0.5}",
                        '{law: "blademodel.components.friction.coulomb:Coulomb", mu: kx}')
    law = load_model(write(tmp_path, text)).contacts[0].friction
    assert type(law) is Coulomb and law.parameters()["mu"].name == "kx"   # a declared parameter


@pytest.mark.parametrize("law, needle", [
    ('"nope.module:Law"', "cannot import friction law 'nope.module:Law'"),
    ('"os:path"', "'os:path' is not a FrictionLaw subclass"),
    ('"blademodel.components:Nope"', "has no 'Nope'"),
])
def test_external_friction_law_errors(tmp_path, law, needle):
    msg = error(tmp_path, GOOD.replace("{law: coulomb, mu: 0.5}", f"{{law: {law}}}"))
    assert "m.yaml:23: contacts.0.friction.law" in msg and needle in msg, msg


def test_external_friction_law_bad_keyword(tmp_path):
    text = GOOD.replace("{law: coulomb, mu: 0.5}",
                        '{law: "blademodel.components.friction.coulomb:Coulomb", bogus: 1}')
    msg = error(tmp_path, text)
    assert ("m.yaml:23: contacts.0.friction.bogus = 1: blademodel.components.friction.coulomb:Coulomb: "
            "unknown option of Coulomb (known: mu, stick_velocity_tol)") in msg, msg


# --- overrides -------------------------------------------------------------------------
def test_overrides_blade_pair():
    base = BladePair()
    out = apply_overrides(base, {"gamma": "5", "gap": "1e-5", "friction": "bilinear", "blade1.m": "0.1"})
    assert (out.gamma, out.gap, out.friction, out.blade1.m) == (5.0, 1e-5, "bilinear", 0.1)
    assert base.gamma == 4.0                       # the original is untouched


@pytest.mark.parametrize("overrides, needles", [
    ({"gama": "5"}, ["gama", "unknown field"]),
    ({"gamma": "-1"}, ["gamma = -1", "greater than or equal to 0"]),
    ({"gamma": "abc"}, ["gamma = 'abc'", "valid number"]),
    ({"gamma": ".nan"}, ["gamma = nan", "finite number"]),
    ({"blade1.q": "1"}, ["blade1.q = 1", "Extra inputs"]),
    ({"gamma.x": "1"}, ["gamma", "no field 'x'"]),
])
def test_override_errors_name_the_field(overrides, needles):
    with pytest.raises(ConfigError) as info:
        apply_overrides(BladePair(), overrides)
    for needle in needles:
        assert needle in str(info.value), str(info.value)


def test_overrides_components():
    config = load_config(MODELS / "blade_row_3.yaml")
    out = apply_overrides(config, {"contacts.0.gap": "1e-5", "omega": "300", "contacts.1.friction.kd": "2e6"})
    assert out.contacts[0].gap == 1e-5
    assert out.parameters["omega"] == 300.0
    assert out.contacts[1].friction.kd == 2e6
    with pytest.raises(ConfigError, match=r"contacts\.7"):
        apply_overrides(config, {"contacts.7.gap": "1"})
    with pytest.raises(ConfigError, match=r"contacts\.0\.friction\.mu = -1"):
        apply_overrides(config, {"contacts.0.friction.mu": "-1"})
    with pytest.raises(ConfigError, match=r"masses\.0\.m = 'mass': unknown parameter"):
        apply_overrides(config, {"masses.0.m": "mass"})


# --- the shipped models ----------------------------------------------------------------
@pytest.mark.parametrize("path", sorted(MODELS.glob("*.yaml")), ids=lambda p: p.name)
def test_shipped_models_load_and_build(path):
    assert isinstance(load_model(path), Model)


@pytest.mark.parametrize("friction", ["coulomb", "bilinear"])
def test_shipped_blade_pair_is_table_1(friction):
    assert load_config(MODELS / f"blade_pair_{friction}.yaml") == BladePair(friction=friction)


def test_general_blade_pair_has_per_blade_symbols():
    model = load_model(MODELS / "blade_pair_general.yaml")
    assert {"m1", "m2", "kx1", "kx2", "ky1", "ky2", "cx1", "cx2", "cy"} <= set(model.parameters)
    assert "cy1" not in model.parameters


def test_friction_oscillator_has_constant_normal_load():
    model = load_model(MODELS / "friction_oscillator.yaml")
    system = derive(model)
    assert system.mode("stick").normal_forces[0] == sp.Symbol("N", real=True)
    assert model.parameters["N"] * model.parameters["mu"] == 10.0


def test_blade_row_derives_16_modes():
    system = derive(load_model(MODELS / "blade_row_3.yaml"))
    names = [m.name for m in system.modes]
    assert len(names) == 16 == len(set(names))
    assert "c12=stick,c23=slip-" in names and "c12=open,c23=open" in names
    assert len(system.q) == 6 and [s.name for s in system.s] == ["z"]


# --- the component format is faithful to the blade pair --------------------------------
FRICTIONS = {
    "coulomb": ({}, {"law": "coulomb", "mu": "mu"}),
    "bilinear": ({"friction": "bilinear"}, {"law": "bilinear", "mu": "mu", "kd": "kd"}),
    "none": ({"friction": "none"}, {"law": "none"}),
    "band": ({"stick": "band", "stick_velocity_tol": 2e-4},
             {"law": "coulomb", "mu": "mu", "stick_velocity_tol": "v_tol"}),
}


@pytest.mark.parametrize("case", list(FRICTIONS))
def test_components_format_builds_the_blade_pair(case):
    pair_kwargs, friction = FRICTIONS[case]
    reference = BladePair(gamma=5.0, **pair_kwargs).build()
    data = yaml.safe_load((MODELS / "blade_pair_components.yaml").read_text())
    data["parameters"].update(k=5.0 * 1e5, kd=1e6, v_tol=2e-4)
    data["contacts"][0]["friction"] = friction
    model = ComponentsModel.model_validate(data).build()

    assert model.structure() == reference.structure()
    assert model.structure_key() == reference.structure_key()
    assert {k: model.parameters[k] for k in reference.parameters} == reference.parameters
    a, b = derive(model), derive(reference)
    assert [m.name for m in a.modes] == [m.name for m in b.modes]
    for ma, mb in zip(a.modes, b.modes):
        for xa, xb in zip(ma.accelerations + ma.friction_forces + ma.normal_forces,
                          mb.accelerations + mb.friction_forces + mb.normal_forces):
            assert sp.simplify(sp.sympify(xa) - sp.sympify(xb)) == 0, ma.name


def test_shipped_components_pair_equals_shipped_blade_pair():
    a = load_model(MODELS / "blade_pair_components.yaml")
    b = load_model(MODELS / "blade_pair_coulomb.yaml")
    assert a.structure() == b.structure()
    assert a.parameters == pytest.approx(b.parameters)


def test_parameters_shared_by_name():
    model = load_model(MODELS / "blade_row_3.yaml")
    omegas = {f.parameters()["omega"].name for f in model.forces}
    assert omegas == {"omega"}
    assert math.isclose(model.parameters["phi3"], 7 * math.pi / 3)
