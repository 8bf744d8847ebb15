"""Result files any NetCDF tool can read: CF coordinates and attributes, strings, the config round trip."""

import json

import numpy as np
import pytest
import xarray as xr

from blademodel.config import config_from_data
from blademodel.sweep import Study, open_result, run_study
from blademodel.sweep.cf import VARIABLES, field_metadata
from blademodel.sweep.point import build_config

STUDY = {"name": "two_laws", "title": "P_d against gamma", "base": {"model": "blade_pair", "omega": 300.0},
         "laws": ["coulomb", "bilinear"], "sweep": {"gamma": {"values": [2.0, 6.0]}},
         "run": {"transient": 10, "periods": 6, "steps_per_period": 200, "vibration_reduction": True}}


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    path = tmp_path_factory.mktemp("cf") / "two_laws.nc"
    run_study(Study.model_validate(STUDY), path, workers=1, progress=None, log=None)
    return path


def test_plain_xarray_sees_named_coordinates_and_strings(result):
    ds = xr.open_dataset(result)
    for dim in ds.dims:   # every dimension has its coordinate variable, except the law's characters
        assert dim in ds.coords, dim
    assert set(ds.coords) >= {"point", "sample", "state", "param_gamma", "law"}
    assert list(ds["point"].values) == [0, 1, 2, 3]
    assert list(ds["law"].values) == ["coulomb", "coulomb", "bilinear", "bilinear"]
    assert all(isinstance(x, str) for x in ds["law"].values)
    assert list(ds["state"].values[:8]) == ["x1", "y1", "x2", "y2", "vx1", "vy1", "vx2", "vy2"]
    assert ds["state"].values[8] == "z"   # the Jenkins slider of the bilinear law: the longer state
    assert ds["error"].values.tolist() == ["", "", "", ""]
    # selection by the coordinates works without blademodel
    bilinear = ds.where(ds.law == "bilinear", drop=True)
    assert np.allclose(bilinear["param_gamma"].values, [2.0, 6.0])
    assert np.isfinite(ds["Pd"].values).all()


def test_cf_attributes(result):
    ds = xr.open_dataset(result)
    assert ds.attrs["Conventions"] == "CF-1.8" and ds.attrs["title"] == "P_d against gamma"
    assert ds.attrs["source"].startswith("blademodel ") and ds.attrs["history"].startswith("created by blademodel")
    for name, var in ds.variables.items():
        assert var.attrs.get("long_name"), f"{name} has no long_name"
        if name in VARIABLES and VARIABLES[name][1]:
            assert var.attrs["units"] == VARIABLES[name][1], name
    assert ds["Pd"].attrs["units"] == "percent" and ds["poincare_vx1"].attrs["units"] == "m s-1"
    assert ds["param_gamma"].attrs["long_name"].startswith("contact stiffness ratio")
    assert "units" not in ds["param_gamma"].attrs   # dimensionless
    assert ds["lyapunov"].encoding.get("coordinates", "").split() == ["param_gamma", "law"]


def test_field_units_come_from_the_config_descriptions():
    cfg = build_config({"model": "blade_pair"}, {})
    assert field_metadata(cfg, "omega") == ("excitation frequency (omega)", "rad s-1")
    assert field_metadata(cfg, "gap") == ("initial shroud gap Delta (gap)", "m")
    assert field_metadata(cfg, "cx") == ("tangential damping (cx)", "N s m-1")
    assert field_metadata(cfg, "mu") == ("friction coefficient (mu)", None)
    assert field_metadata(cfg, "no.such") == ("swept field no.such", None)


def test_the_study_and_the_config_round_trip(result):
    ds = xr.open_dataset(result)
    study = Study.model_validate(json.loads(ds.attrs["study"]))
    assert study == Study.model_validate(STUDY)
    config = config_from_data(json.loads(ds.attrs["config"]), source="file")
    assert config == build_config(STUDY["base"], {})
    assert config.omega == 300.0 and config.gamma == 4.0   # the base's value and a default, both stored
    import blademodel
    opened = blademodel.open_result(result)
    assert opened.attrs["config"] == json.loads(ds.attrs["config"])


@pytest.mark.slow   # a cold compile of its own tangent (~45 s in CI); test_continuation.py round-trips branch files
def test_a_branch_file_is_cf_and_plot_draws_it(tmp_path, capsys):
    """``continue --out`` writes a CF file with named coordinates; ``blademodel plot`` draws its forced response."""
    from matplotlib.image import imread

    from blademodel.cli import main
    from blademodel.orbits.branch_file import load_branch

    model = tmp_path / "oscillator.yaml"
    model.write_text("""model: components
name: oscillator
parameters: {omega: 9.0}
masses: [{name: m, m: 1.0, dofs: [x]}]
springs: [{a: x_m, k: 100.0}]
dampers: [{a: x_m, c: 0.5}]
forces: [{mass: m, amplitude: 1.0, omega: omega}]
""")
    branch_nc = tmp_path / "branch.nc"
    assert main(["continue", str(model), "--param", "omega", "--from", "9", "--to", "11", "--out", str(branch_nc),
                 "--max-points", "12", "--steps-per-period", "200"]) == 0
    # closed before plot reads it: netCDF-C 4.10 / HDF5 2.2 crashed reading the file's attributes again while
    # xarray held it open in the same process (after a full read of the branch)
    with xr.open_dataset(branch_nc) as ds:
        assert ds.attrs["Conventions"] == "CF-1.8"
        for dim in ds.dims:
            assert dim in ds.coords, dim
        assert "omega" in ds.coords and ds["amplitude"].encoding["coordinates"] == "omega"
        assert all(var.attrs.get("long_name") for var in ds.variables.values())
    capsys.readouterr()
    assert main(["plot", str(branch_nc)]) == 0
    png = tmp_path / "branch_branch.png"
    assert capsys.readouterr().out.split() == [str(png), str(tmp_path / "branch_reduction.png")]
    for drawn in (png, tmp_path / "branch_reduction.png"):
        image = imread(drawn)
        assert image.shape[0] > 100 and image[..., :3].std() > 0.01   # drawn, not blank
    branch = load_branch(branch_nc)
    # no contacts: the orbits are the reference's own, P_d zero but for RK4's error at 200 steps a period
    from blademodel.commands.plot import _branch_reduction
    from blademodel.orbits.branch_file import branch_origin
    names, pd = _branch_reduction(branch_origin(branch_nc)[1], branch, branch_nc)
    assert names == "x_m" and np.max(np.abs(pd)) < 1e-4
    # the exact linear FRF at the branch's ends: |X| = F0 / sqrt((k - m w^2)^2 + (c w)^2)
    w = branch.params
    exact = 1.0 / np.sqrt((100.0 - w ** 2) ** 2 + (0.5 * w) ** 2)
    np.testing.assert_allclose(np.abs(branch.harmonics[:, 0]), exact, rtol=1e-6)


def test_plot_refuses_a_file_that_is_no_result(tmp_path):
    from blademodel.cli import main

    other = tmp_path / "other.nc"
    xr.Dataset({"a": ("x", [1.0, 2.0])}).to_netcdf(other)
    assert main(["plot", str(other)]) != 0
