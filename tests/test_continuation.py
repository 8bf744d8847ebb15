"""Pseudo-arclength continuation of periodic orbits: exact linear FRF, period doubling, a switch at the section."""

import numpy as np
import pytest

from blademodel.analysis.periodicity import poincare_period
from blademodel.config import BladePair
from blademodel.numeric import simulate
from blademodel.numeric.kernels import make_integrator
from blademodel.orbits import PeriodMap, continuation, find_periodic_orbit
from linear_reference import forced_response


def _exact_first_harmonic(cfg, omega, state="x1"):
    """The exact first harmonic of ``state`` of the contact-free model at ``omega``."""
    ig = make_integrator(type(cfg).model_validate({**cfg.model_dump(), "omega": omega}).build())
    return forced_response(ig)[list(ig.meta["state"]).index(state)]


def test_the_forced_response_of_a_contact_free_pair_is_the_exact_linear_frf():
    """Continued in omega through the tangential resonance (1085 rad/s) with RK8: every point's first harmonic
    equals the exact linear response to 1e-8, every orbit is stable and no bifurcation is reported."""
    cfg = BladePair(gap=1.0)
    b = continuation(cfg, "omega", 1000.0, 1200.0, method="rk8", ds_max=0.1)
    assert b.params[-1] >= 1200.0 and np.all(np.diff(b.params) > 0) and len(b.params) > 20
    i = b.state_names.index("x1")
    exact = np.array([_exact_first_harmonic(cfg, w) for w in b.params])
    assert np.max(np.abs(b.harmonics[:, i] - exact) / np.abs(exact)) < 1e-8
    peak = np.argmax(np.abs(exact))
    assert 0 < peak < len(exact) - 1     # the peak lies inside the branch, followed through
    assert b.stable.all() and b.special == []


@pytest.fixture(scope="module")
def pd_branch():
    return continuation(BladePair(friction="bilinear"), "gamma", 6.5, 8.0)


def test_a_period_doubling_of_the_bilinear_pair_in_gamma(pd_branch):
    """The period-1 branch of the bilinear pair loses stability through -1 (gamma ~ 7.325).

    Checked independently of the difference quotients: just below the located value the orbit is what an
    integration from rest settles on (period 1), just above an integration from rest does not settle on
    period 1, and a small displacement along the critical eigenvector, integrated, flips sign every period
    and decays below, grows above."""
    cfg, b = BladePair(friction="bilinear"), pd_branch
    assert b.params[-1] >= 8.0
    pds = b.points("period-doubling")
    assert len(b.special) == 1 and len(pds) == 1
    g = pds[0].param
    assert abs(pds[0].multiplier + 1) < 1e-4
    below, above = g - 0.005, g + 0.005
    runs = {v: simulate(type(cfg).model_validate({**cfg.model_dump(), "gamma": v}).build(), transient=1500,
                        periods=32) for v in (below, above)}
    assert poincare_period(runs[below].poincare[:, :8]) == 1 and poincare_period(runs[above].poincare[:, :8]) != 1
    for v, grows in ((below, False), (above, True)):
        m = type(cfg).model_validate({**cfg.model_dump(), "gamma": v}).build()
        ig = make_integrator(m)
        o = find_periodic_orbit(m, integrator=ig, guess=b.states[np.argmin(np.abs(b.params - v))], transient=0)
        mu = o.largest_multiplier
        assert mu.real < 0 and abs(mu.imag) < 1e-9 and (abs(mu) > 1) == grows
        w, V = np.linalg.eig(o.monodromy)
        v0 = np.real(V[:, np.argmin(np.abs(w - mu))])
        P = PeriodMap(ig, 1)
        y0 = o.state + 1e-6 * v0 / np.max(np.abs(v0 / o.scale))
        d0 = (y0 - o.state) / o.scale
        y1, _ = P(y0, o.mode)
        d1 = (y1 - o.state) / o.scale
        assert np.dot(d1, d0) / np.dot(d0, d0) == pytest.approx(mu.real, rel=1e-2)


def test_the_branch_crosses_a_stick_slip_switch_at_the_section():
    """Near gamma = 4.5253 the orbit's stick-to-slip switch passes t = 0, a kink of the period map: the branch
    goes through, and its points there are the orbits shooting finds at those values."""
    cfg = BladePair(friction="bilinear")
    b = continuation(cfg, "gamma", 4.45, 4.65)
    assert b.params[-1] >= 4.65 and np.all(np.diff(b.params) > 0)
    assert b.params.min() < 4.5253 < b.params.max()
    for k in (np.argmin(np.abs(b.params - 4.52)), np.argmin(np.abs(b.params - 4.55))):
        m = type(cfg).model_validate({**cfg.model_dump(), "gamma": b.params[k]}).build()
        o = find_periodic_orbit(m, transient=200)
        assert np.max(np.abs(o.state - b.states[k]) / o.scale) < 1e-8


def test_a_branch_file_round_trip(pd_branch, tmp_path):
    """The NetCDF file holds the branch (and opens in xarray with the state names as a coordinate)."""
    import xarray as xr

    from blademodel.orbits.branch_file import load_branch, save_branch
    path = tmp_path / "b.nc"
    save_branch(pd_branch, path, BladePair(friction="bilinear"))
    back = load_branch(path)
    assert np.array_equal(back.params, pd_branch.params) and np.array_equal(back.states, pd_branch.states)
    assert np.array_equal(back.multipliers, pd_branch.multipliers) and np.array_equal(back.stable, pd_branch.stable)
    assert np.allclose(back.harmonics, pd_branch.harmonics, rtol=1e-14, atol=0)
    assert [(p.kind, p.param) for p in back.special] == [(p.kind, p.param) for p in pd_branch.special]
    with xr.open_dataset(path) as ds:
        assert list(ds["state"].values) == pd_branch.state_names and ds.attrs["field"] == "gamma"
        assert '"friction": "bilinear"' in ds.attrs["config"]


def test_the_continue_command(tmp_path, capsys):
    """``blademodel continue``: the JSON report, the file and the plot; a missing field is named."""
    import json
    from pathlib import Path

    from blademodel.cli import main
    yaml = str(Path(__file__).resolve().parent.parent / "models" / "blade_pair_bilinear.yaml")
    out, png = tmp_path / "b.nc", tmp_path / "b.png"
    assert main(["continue", yaml, "--param", "gamma", "--from", "7.2", "--to", "7.5", "--json",
                 "--out", str(out), "--plot", str(png)]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert [p["kind"] for p in rep["special"]] == ["period-doubling"] and 7.3 < rep["special"][0]["value"] < 7.35
    assert rep["stable"][0] and not rep["stable"][-1] and out.stat().st_size > 0 and png.stat().st_size > 0
    assert main(["continue", yaml, "--param", "no_such_field", "--from", "1", "--to", "2"]) == 2
    assert "no field 'no_such_field'" in capsys.readouterr().err
