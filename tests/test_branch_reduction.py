"""The vibration reduction P_d along a branch: its reference P0 in closed form, its P from each orbit."""

import json
from pathlib import Path

import numpy as np
import pytest

from blademodel.analysis.contact_free import contact_free_mean_squares
from blademodel.cli import main
from blademodel.config import BladedDisk
from blademodel.numeric.mean_square import mean_square_run, without_contacts
from blademodel.orbits import continuation
from blademodel.orbits.branch_reduction import branch_vibration_reduction
from blademodel.sweep.point import run_point
from blademodel.zheng2022 import BladePair

MODELS = Path(__file__).resolve().parents[1] / "models"


@pytest.mark.parametrize("model", [BladePair(friction="bilinear").build(),
                                   BladedDisk(blades=4, engine_order=1, omega=286.0, mistuning_std=0.05,
                                              mistuning_seed=2).build()], ids=["pair", "mistuned ring"])
def test_the_contact_free_steady_state_is_the_one_integration_settles_on(model):
    """The closed-form mean squares of the model without contacts are those a long RK4 run from rest settles on
    (the sweeps' P0), to 1e-8: 400 periods of transient, the mean over 10 more."""
    ms = contact_free_mean_squares(model)
    names = list(model.masses[0].coordinates)
    P0 = sum(ms[n] for n in names)
    integrated = mean_square_run(without_contacts(model), transient=400, periods=10, steps_per_period=1000,
                                 names=names)
    assert abs(P0 - integrated) / P0 < 1e-8
    other = list(model.masses[-1].coordinates)   # another mass, with another phase of the forcing
    assert abs(sum(ms[n] for n in other) - mean_square_run(without_contacts(model), transient=400, periods=10,
                                                           steps_per_period=1000, names=other)) / P0 < 1e-8


@pytest.mark.parametrize("law", ["bilinear", "coulomb"])
def test_p_d_along_a_branch_is_the_sweeps_at_its_stable_points(law):
    """At two stable points of a branch in gamma, P_d from the orbit's mean square and the closed-form P0 is what
    a sweep point gives (300 periods from rest, P and P0 each integrated): to 1e-6 percentage points (measured
    3e-8, the sweep's P0 settling)."""
    cfg = BladePair(friction=law)
    b = continuation(cfg, "gamma", 3.5, 4.5, workers=1)
    pd = branch_vibration_reduction(b, cfg)
    assert np.all(np.isfinite(pd)) and pd.shape == b.params.shape
    for g0 in (3.7, 4.3):
        i = int(np.argmin(np.abs(b.params - g0)))
        assert b.stable[i]
        r = run_point(cfg.model_dump(), {"gamma": float(b.params[i])},
                      {"transient": 300, "periods": 20, "steps_per_period": 1000, "event_tol": 1e-10,
                       "history_periods": 0, "vibration_reduction": True})
        assert abs(pd[i] - r["Pd"]) < 1e-6
        assert 30 < pd[i] < 60   # the shroud removes about half (the paper's Fig. 17 at gamma = 4)


def test_a_contact_that_never_touches_removes_nothing():
    """With a gap far beyond the blades' motion the orbits are the contact-free model's: P_d is zero but for the
    integration's error on P (RK4, 1000 steps a period: about 1e-9 of P)."""
    cfg = BladePair(friction="coulomb", gap=1e-2)
    b = continuation(cfg, "omega", 280.0, 300.0, max_points=8, workers=1)
    assert np.all(b.events == 0)
    pd = branch_vibration_reduction(b, cfg)
    assert np.max(np.abs(pd)) < 1e-6


def test_p_d_comes_with_the_branch_file_and_the_command(tmp_path, capsys):
    """The orbits' mean squares round-trip through the branch file (P_d from the file is the branch's); the
    command prints P_d's range, writes it in its JSON and draws it; a file without mean squares (written before
    they were kept) gives NaN."""
    import netCDF4
    from blademodel.orbits.branch_file import load_branch, save_branch
    cfg = BladePair(friction="bilinear")
    b = continuation(cfg, "gamma", 3.9, 4.1, workers=1)
    path = tmp_path / "b.nc"
    save_branch(b, path, cfg)
    back = load_branch(path)
    np.testing.assert_array_equal(back.mean_squares, b.mean_squares)
    np.testing.assert_array_equal(branch_vibration_reduction(back, cfg), branch_vibration_reduction(b, cfg))
    with netCDF4.Dataset(path, "a") as ds:
        ds.renameVariable("mean_square", "unknown")
    assert np.all(np.isnan(branch_vibration_reduction(load_branch(path), cfg)))
    model = str(MODELS / "blade_pair_bilinear.yaml")
    assert main(["continue", model, "--param", "gamma", "--from", "3.9", "--to", "4.1", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(rep["P_d"], branch_vibration_reduction(b, cfg), rtol=0, atol=1e-9)
    png = tmp_path / "pd.png"
    assert main(["continue", model, "--param", "gamma", "--from", "3.9", "--to", "4.1", "--quantity", "reduction",
                 "--plot", str(png)]) == 0
    out = capsys.readouterr().out
    assert png.stat().st_size > 0 and "vibration reduction P_d of x1, y1: " in out


def test_the_plot_draws_the_values_given_for_the_reduction():
    from blademodel.plots.branch import branch_figure
    cfg = BladePair(friction="bilinear")
    b = continuation(cfg, "gamma", 3.9, 4.1, workers=1)
    pd = branch_vibration_reduction(b, cfg)
    fig = branch_figure(b, "x1, y1", quantity="reduction", values=[pd])
    ax = fig.axes[0]
    drawn = [line for line in ax.lines if len(line.get_xdata()) > 1 and line.get_linewidth() == 1.6]
    ys = np.concatenate([line.get_ydata() for line in drawn])
    assert set(np.round(ys, 12)) == set(np.round(pd, 12)) and "P_d" in ax.get_ylabel()
    with pytest.raises(ValueError, match="P_d in values"):
        branch_figure(b, "x1", quantity="reduction")


def test_a_tuned_ring_s_mean_squares_on_the_reduced_map_are_the_whole_orbit_s():
    """On the map over T / 8 (cyclic) a point's mean squares come from the whole period rebuilt from the reduced
    one: they are those of the orbit solved on the whole ring's map at that frequency, to 1e-12, and alike for
    every blade (a travelling wave)."""
    from blademodel.config import apply_overrides, load_config
    from blademodel.orbits import find_periodic_orbit
    cfg = load_config(MODELS / "bladed_disk_24.yaml")
    b = continuation(cfg, "omega", 280.0, 281.0, cyclic=True, max_points=2, workers=1)
    orbit = find_periodic_orbit(apply_overrides(cfg, {"omega": float(b.params[1])}).build(), guess=b.states[1],
                                mode=b.modes[1], workers=1)
    whole = np.mean(orbit.y[:-1] ** 2, axis=0)
    assert np.max(np.abs(b.mean_squares[1] - whole)) < 1e-12 * np.max(whole)
    x = b.mean_squares[1][[b.state_names.index(f"x{i}") for i in range(1, 25)]]
    assert np.ptp(x) < 1e-12 * np.max(x)


def test_the_orbit_command_reports_the_p_d_of_its_orbit(capsys):
    """``blademodel orbit`` at gamma = 4 reports the P_d that the branch's first point at gamma = 4 has."""
    cfg = BladePair(friction="bilinear")
    b = continuation(cfg, "gamma", 4.0, 4.05, max_points=2, workers=1)
    model = str(MODELS / "blade_pair_bilinear.yaml")
    assert main(["orbit", model, "--set", "gamma=4", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert abs(rep["P_d"] - branch_vibration_reduction(b, cfg)[0]) < 1e-8


def test_a_sweep_s_p_d_is_overlaid_on_the_branch_s(tmp_path, capsys):
    """``--quantity reduction --overlay SWEEP.nc`` draws the sweep's P_d on the branch's: the overlay is the file's
    P_d of the config's law, which at a stable point of the branch is the branch's P_d to 1e-4 percentage points
    (the sweep's 300 periods from rest); a sweep without P_d is refused before any continuation, naming the
    setting that gives it."""
    from blademodel.commands.continue_ import sweep_overlay
    from blademodel.sweep.runner import open_result
    study = tmp_path / "study.yaml"
    study.write_text("name: pd\nbase: {model: blade_pair, gap: 4.0e-05, F0: 60}\nlaws: [coulomb, bilinear]\n"
                     "sweep:\n  gamma: {start: 3.6, stop: 4.4, num: 3}\n"
                     "run: {transient: 300, periods: 10, vibration_reduction: true}\n")
    nc = tmp_path / "pd.nc"
    assert main(["sweep", str(study), "--out", str(nc), "--workers", "1", "--no-plot"]) == 0
    values, pd = sweep_overlay(nc, "gamma", 0, "bilinear", "reduction")
    ds = open_result(nc)
    bilinear = ds["law"].values == "bilinear"
    np.testing.assert_array_equal(values, ds["param_gamma"].values[bilinear])
    np.testing.assert_array_equal(pd, ds["Pd"].values[bilinear])
    cfg = BladePair(friction="bilinear")
    b = continuation(cfg, "gamma", 3.6, 4.4, workers=1)
    assert abs(b.params[0] - values[0]) < 1e-12 and b.stable[0]
    assert abs(branch_vibration_reduction(b, cfg)[0] - pd[0]) < 1e-4
    model = str(MODELS / "blade_pair_bilinear.yaml")
    png = tmp_path / "pd.png"
    capsys.readouterr()
    assert main(["continue", model, "--param", "gamma", "--from", "3.6", "--to", "4.4", "--quantity", "reduction",
                 "--overlay", str(nc), "--plot", str(png)]) == 0 and png.stat().st_size > 0
    plain = tmp_path / "plain.yaml"
    plain.write_text(study.read_text().replace(", vibration_reduction: true", ""))
    assert main(["sweep", str(plain), "--out", str(tmp_path / "plain.nc"), "--workers", "1", "--no-plot"]) == 0
    capsys.readouterr()
    assert main(["continue", model, "--param", "gamma", "--from", "3.6", "--to", "4.4", "--quantity", "reduction",
                 "--overlay", str(tmp_path / "plain.nc"), "--plot", str(png)]) == 2
    assert "holds no P_d (run it with run.vibration_reduction: true)" in capsys.readouterr().err
