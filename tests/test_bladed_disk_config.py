"""The bladed-disk config: a ring of N blades and N contacts, engine-order phases,
mistuning, per-contact overrides, errors that name the field and the value.
Builds models only; nothing is integrated."""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np
import pytest
from pydantic import ValidationError

from blademodel.components import Coulomb, Iwan, Jenkins
from blademodel.config import BladedDisk, ConfigError, apply_overrides, load_config, load_model
from blademodel.config.kinds import model_kinds

MODELS = Path(__file__).resolve().parents[1] / "models"


def write(tmp_path, text, name="disk.yaml"):
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


def spring(model, coordinate):
    return next(s for s in model.springs if s.a == coordinate).parameters()["k"]


# --- topology -------------------------------------------------------------------------------
@pytest.mark.parametrize("n", [2, 3, 7, 24])
def test_ring_of_n_masses_and_n_contacts(n):
    model = BladedDisk(blades=n).build()
    assert [m.name for m in model.masses] == [str(i) for i in range(1, n + 1)]
    assert all(m.dofs == ("x", "y") for m in model.masses)
    assert len(model.coordinates) == 2 * n
    assert [c.name for c in model.contacts] == [f"c{i}" for i in range(1, n + 1)]
    for i, c in enumerate(model.contacts):
        assert (c.body1.name, c.body2.name) == (str(i + 1), str((i + 1) % n + 1))
    assert (model.contacts[-1].body1.name, model.contacts[-1].body2.name) == (str(n), "1")
    # every blade touches exactly two contacts, once as body 1 and once as body 2
    assert sorted(c.body1.name for c in model.contacts) == sorted(c.body2.name for c in model.contacts)
    assert len(model.springs) == len(model.dampers) == 2 * n and len(model.forces) == n


def test_without_contacts_and_scales():
    disk = BladedDisk(blades=5, gap=3e-5, gamma=2.5, omega=300.0)
    assert disk.build(contact=False).contacts == ()
    assert disk.period == 2 * math.pi / 300.0
    assert disk.length_scale == 3e-5 == disk.build().length_scale
    assert disk.k == 2.5 * 1e5
    assert BladedDisk(gamma_reference="ky").k == 4.0 * 3e6


def test_tuned_disk_uses_shared_symbols():
    params = BladedDisk(blades=4).build().parameters
    for name in ("m", "kx", "ky", "cx", "cy", "F0", "omega", "beta", "Delta", "alpha", "k", "mu"):
        assert name in params
    assert not any(f"{n}{i}" in params for n in ("m", "kx", "ky", "cx", "cy") for i in range(1, 5))
    assert [p for p in params if p.startswith("phi")] == ["phi1", "phi2", "phi3", "phi4"]
    assert params["k"] == 4e5 and params["Delta"] == 4e-5


# --- excitation -----------------------------------------------------------------------------
@pytest.mark.parametrize("n, eo, phase0", [(24, 3, math.pi / 3), (7, 2, 0.25), (10, 0, -1.0), (12, 13, 0.0)])
def test_force_phases_follow_the_engine_order(n, eo, phase0):
    disk = BladedDisk(blades=n, engine_order=eo, phase0=phase0)
    forces = disk.build().forces
    for i, f in enumerate(forces):
        p = f.parameters()
        assert f.mass.name == str(i + 1)
        assert p["phase"].name == f"phi{i + 1}"
        assert p["phase"].value == phase0 + 2 * math.pi * eo * i / n   # exactly
        assert (p["amplitude"].name, p["omega"].name, p["angle"].name) == ("F0", "omega", "beta")
        assert p["angle"].value == math.pi / 6


# --- mistuning ------------------------------------------------------------------------------
def test_mistuning_list_scales_kx_and_ky_of_its_blade():
    delta = [0.0] * 6
    delta[2], delta[5] = 0.1, -0.05
    disk = BladedDisk(blades=6, mistuning=delta)
    model = disk.build()
    np.testing.assert_array_equal(disk.deviations, delta)
    for i in range(6):
        kx, ky = spring(model, f"x{i + 1}"), spring(model, f"y{i + 1}")
        assert (kx.name, ky.name) == (f"kx{i + 1}", f"ky{i + 1}")
        assert kx.value == 1e5 * (1 + delta[i]) and ky.value == 3e6 * (1 + delta[i])
    assert spring(model, "x3").value == pytest.approx(1.1e5) and spring(model, "y6").value == pytest.approx(2.85e6)
    assert spring(model, "x1").value == 1e5
    assert all(c.parameters()["k"].value == 4e5 for c in model.contacts)   # the tuned kx
    assert model.parameters["m"] == 0.085   # other values stay shared


def test_seeded_mistuning_draw_is_reproducible():
    a = BladedDisk(blades=24, mistuning_std=0.03, mistuning_seed=7)
    expected = np.random.default_rng(7).normal(0, 0.03, 24)
    np.testing.assert_array_equal(a.deviations, expected)
    np.testing.assert_array_equal(BladedDisk(blades=24, mistuning_std=0.03, mistuning_seed=7).deviations, expected)
    assert not np.array_equal(BladedDisk(blades=24, mistuning_std=0.03, mistuning_seed=8).deviations, expected)
    model = a.build()
    assert [spring(model, f"x{i + 1}").value for i in range(24)] == [1e5 * (1 + d) for d in expected]
    assert [spring(model, f"y{i + 1}").value for i in range(24)] == [3e6 * (1 + d) for d in expected]
    np.testing.assert_array_equal(BladedDisk(mistuning_std=0.02).deviations,
                                  np.random.default_rng(0).normal(0, 0.02, 24))   # default seed 0


def test_tuned_deviations_are_zeros():
    disk = BladedDisk(blades=5)
    np.testing.assert_array_equal(disk.deviations, np.zeros(5))
    assert not disk.mistuned


# --- per-blade and per-contact values -------------------------------------------------------
def test_contact_overrides_get_per_contact_symbols():
    disk = BladedDisk(blades=6, contacts={2: {"gap": 2e-5, "gamma": 5.0, "mu": 0.3, "alpha": 1.0},
                                          4: {"friction": "bilinear", "kd": 2e6}})
    model = disk.build()
    c3, c5 = model.contacts[2].parameters(), model.contacts[4].parameters()
    assert (c3["gap"].name, c3["gap"].value) == ("Delta_c3", 2e-5)
    assert (c3["k"].name, c3["k"].value) == ("k_c3", 5.0 * 1e5)
    assert (c3["alpha"].name, c3["alpha"].value) == ("alpha_c3", 1.0)
    assert model.contacts[2].friction.parameters()["mu"].name == "mu_c3"
    assert model.contacts[2].friction.parameters()["mu"].value == 0.3
    assert isinstance(model.contacts[4].friction, Jenkins)
    assert model.contacts[4].friction.parameters()["kd"].name == "kd_c5"
    assert model.contacts[4].friction.parameters()["mu"].name == "mu"
    assert isinstance(model.contacts[0].friction, Coulomb)
    assert model.contacts[0].parameters()["gap"].name == "Delta"
    assert model.parameters["Delta"] == 4e-5 and model.parameters["k"] == 4e5


def test_contact_friction_options_follow_its_law():
    disk = BladedDisk(blades=3, friction="iwan", friction_options={"elements": 3},
                      contacts={0: {"friction": "coulomb"}, 1: {"friction_options": {"elements": 2}}})
    model = disk.build()
    laws = [c.friction for c in model.contacts]
    assert isinstance(laws[0], Coulomb)
    assert isinstance(laws[1], Iwan) and laws[1].elements == 2
    assert isinstance(laws[2], Iwan) and laws[2].elements == 3


def test_blade_values_get_per_blade_symbols():
    model = BladedDisk(blades=4, blade_values={1: {"m": 0.09, "cx": 4.0}}).build()
    assert model.masses[1].parameters()["m"].name == "m2" and model.parameters["m2"] == 0.09
    assert model.masses[0].parameters()["m"].name == "m" and model.parameters["m"] == 0.085
    assert model.parameters["cx2"] == 4.0 and model.parameters["cx"] == 3.5


# --- errors ---------------------------------------------------------------------------------
@pytest.mark.parametrize("text, expected", [
    ("model: bladed_disk\nblades: 1\n", "disk.yaml:2: blades = 1: Input should be greater than or equal to 2"),
    ("model: bladed_disk\nblades: yes\n", "disk.yaml:2: blades = True: Input should be a valid integer"),
    ("model: bladed_disk\nengine_order: -2\n",
     "disk.yaml:2: engine_order = -2: Input should be greater than or equal to 0"),
    ("model: bladed_disk\nengine_order: 1.5\n", "disk.yaml:2: engine_order = 1.5: Input should be a valid integer"),
    ("model: bladed_disk\nblades: 3\nmistuning: [0.1, 0.2]\n",
     "disk.yaml:3: mistuning = [0.1, 0.2]: has 2 values; blades = 3 needs one per blade"),
    ("model: bladed_disk\nblades: 3\nmistuning: [0.1, -1.5, 0]\n",
     "disk.yaml:3: mistuning.1 = -1.5: Input should be greater than -1"),
    ("model: bladed_disk\nblades: 3\nmistuning: [0.1, 0.0, 0]\nmistuning_std: 0.02\n",
     "disk.yaml:4: mistuning_std = 0.02: give either mistuning"),
    ("model: bladed_disk\nmistuning_std: -0.1\n",
     "disk.yaml:2: mistuning_std = -0.1: Input should be greater than or equal to 0"),
    ("model: bladed_disk\nblades: 200\nmistuning_std: 0.5\n",
     "disk.yaml:3: mistuning_std = 0.5: mistuning_seed = 0 draws delta_12 = -1.163 <= -1"),
    ("model: bladed_disk\nblades: 4\ncontacts:\n  1: {gap: 1e-5}\n  4: {gap: 2e-5}\n",
     "disk.yaml:5: contacts.4 = 4: no contact 4: contacts are numbered 0..3 (blades = 4)"),
    ("model: bladed_disk\nblades: 4\nblade_values:\n  -1: {m: 0.1}\n",
     "disk.yaml:4: blade_values.-1 = -1: no blade -1: blades are numbered 0..3"),
    ("model: bladed_disk\ncontacts:\n  2: {gap: 1e-5, mu: -1}\n",
     "disk.yaml:3: contacts.2.mu = -1: Input should be greater than or equal to 0"),
    ("model: bladed_disk\ncontacts:\n  2: {friction: magic}\n",
     "disk.yaml:3: contacts.2.friction = 'magic': unknown friction law 'magic'"),
    ("model: bladed_disk\ncontacts:\n  2:\n    friction: iwan\n    friction_options: {elements: 0}\n",
     "disk.yaml:5: contacts.2.friction_options.elements = 0: iwan: elements = 0 must be an integer >= 1"),
    ("model: bladed_disk\ncontacts:\n  2: {friction_options: {mu: 0.2}}\n",
     "disk.yaml:3: contacts.2.friction_options.mu = 0.2: 'mu' is a field of the contact"),
    ("model: bladed_disk\nfriction_options: {kd: 3}\n",
     "disk.yaml:2: friction_options.kd = 3: 'kd' is a field of the disk"),
    ("model: bladed_disk\nphi1: 0.5\n", "disk.yaml:2: phi1 = 0.5: Extra inputs are not permitted"),
])
def test_errors_name_line_field_and_value(tmp_path, text, expected):
    msg = error(tmp_path, text)
    assert expected in msg, msg


def test_errors_without_a_file_name_field_and_value():
    cases = [
        (dict(blades=1), "blades"),
        (dict(blades=4, mistuning=[0.0] * 3), "mistuning = [0.0, 0.0, 0.0]: has 3 values; blades = 4"),
        (dict(blades=4, mistuning=[0.0] * 4, mistuning_std=0.1), "mistuning_std = 0.1: give either"),
        (dict(blades=4, contacts={9: {"gap": 1e-5}}), "contacts.9 = 9: no contact 9"),
    ]
    for kwargs, needle in cases:
        with pytest.raises(ValidationError) as info:
            BladedDisk(**kwargs)
        assert needle in str(info.value), str(info.value)
    with pytest.raises(ValidationError, match="input_value=1"):
        BladedDisk(blades=1)


def test_yaml_syntax_error_gives_file_and_line(tmp_path):
    msg = error(tmp_path, "model: bladed_disk\nblades: 24\nmistuning: [0.1, 0.2\ngap: 1e-5\n")
    assert "disk.yaml:4: YAML syntax error" in msg, msg


# --- files and overrides --------------------------------------------------------------------
def test_registered_format():
    assert model_kinds()["bladed_disk"] is BladedDisk


def test_example_file_loads():
    disk = load_config(MODELS / "bladed_disk_24.yaml")
    assert isinstance(disk, BladedDisk)
    assert (disk.blades, disk.engine_order, disk.friction, disk.mistuned) == (24, 3, "coulomb", False)
    assert disk == BladedDisk(engine_order=3)   # every value written out is the default
    model = load_model(MODELS / "bladed_disk_24.yaml")
    assert len(model.masses) == len(model.contacts) == 24
    assert all(isinstance(c.friction, Coulomb) for c in model.contacts)
    assert model.parameters["phi2"] - model.parameters["phi1"] == pytest.approx(math.pi / 4)


def test_bilinear_example_file_loads():
    disk = load_config(MODELS / "bladed_disk_24_bilinear.yaml")
    assert (disk.blades, disk.engine_order, disk.friction) == (24, 3, "bilinear")
    assert all(isinstance(c.friction, Jenkins) for c in disk.build().contacts)


def test_overrides():
    base = load_config(MODELS / "bladed_disk_24.yaml")
    big = apply_overrides(base, {"blades": "48"})
    model = big.build()
    assert big.blades == 48 and len(model.masses) == 48 and len(model.contacts) == 48
    last = model.contacts[-1]
    assert (last.name, last.body1.name, last.body2.name) == ("c48", "48", "1")
    assert model.forces[5].parameters()["phase"].value == base.phase0 + 2 * math.pi * 3 * 5 / 48
    assert apply_overrides(base, {"engine_order": "5"}).engine_order == 5
    mistuned = apply_overrides(base, {"mistuning_std": "0.02"})
    np.testing.assert_array_equal(mistuned.deviations, np.random.default_rng(0).normal(0, 0.02, 24))
    assert spring(mistuned.build(), "x1").name == "kx1"
    swept = apply_overrides(base, {"engine_order": 2.0, "gap": 3e-5})   # sweep values are floats
    assert swept.engine_order == 2 and swept.build().parameters["Delta"] == 3e-5


def test_override_of_a_contact_by_index():
    base = BladedDisk(blades=4, contacts={2: {"gap": 1e-5}})
    out = apply_overrides(base, {"contacts.2.gap": "2e-5", "contacts.2.mu": "0.2"})
    assert (out.contacts[2].gap, out.contacts[2].mu) == (2e-5, 0.2)
    assert out.build().parameters["Delta_c3"] == 2e-5


@pytest.mark.parametrize("overrides, needle", [
    ({"blades": "1"}, "blades = 1"),
    ({"blades": "3", "mistuning": "[0.1, 0.1]"}, "mistuning = [0.1, 0.1]: has 2 values; blades = 3"),
    ({"engine_order": "-1"}, "engine_order = -1"),
])
def test_bad_overrides_name_field_and_value(overrides, needle):
    with pytest.raises(ConfigError) as info:
        apply_overrides(BladedDisk(), overrides)
    assert needle in str(info.value), str(info.value)


def test_fewer_blades_than_an_overridden_contact_is_an_error():
    base = BladedDisk(blades=24, contacts={20: {"gap": 1e-5}})
    with pytest.raises(ConfigError, match=r"contacts\.20 = 20: no contact 20: contacts are numbered 0\.\.11"):
        apply_overrides(base, {"blades": "12"})
