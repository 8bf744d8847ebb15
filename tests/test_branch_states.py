"""The states a branch's report and plot show: a name or a pattern (``blademodel.orbits.branch_states``), whose
largest and smallest first harmonics at each point are a mistuned ring's envelope; in the plot, ``continue --state``
and ``plot --state``."""

import json
from pathlib import Path

import numpy as np
import pytest

from blademodel.orbits.branch_states import envelope, state_indices

MODELS = Path(__file__).resolve().parent.parent / "models"
NAMES = ["x1", "y1", "x2", "y2", "x10", "vx1"]


def test_a_name_is_one_state_and_a_pattern_every_state_it_matches_in_order():
    assert state_indices(NAMES, "y2") == [3]
    assert state_indices(NAMES, "x*") == [0, 2, 4]       # not vx1
    assert state_indices(NAMES, "x?") == [0, 2]
    assert state_indices(NAMES, "[xy]1") == [0, 1]
    with pytest.raises(ValueError, match=r"--state 'x3': not a state of the model \(x1, y1"):
        state_indices(NAMES, "x3", "--state")
    with pytest.raises(ValueError, match=r"state 'z\*': the pattern matches no state"):
        state_indices(NAMES, "z*")


def test_the_envelope_is_the_largest_and_smallest_modulus_and_says_whose():
    rng = np.random.default_rng(3)
    h = rng.normal(size=(7, 6)) + 1j * rng.normal(size=(7, 6))
    largest, smallest, which = envelope(h, [0, 2, 4])
    mags = np.abs(h[:, [0, 2, 4]])
    for k in range(7):
        assert largest[k] == max(mags[k]) and smallest[k] == min(mags[k])
        assert which[k] in (0, 2, 4) and mags[k][[0, 2, 4].index(which[k])] == largest[k]
    one, same, who = envelope(h, [3])
    assert np.array_equal(one, np.abs(h[:, 3])) and np.array_equal(same, one) and set(who) == {3}


@pytest.fixture(scope="module")
def ring_branch(tmp_path_factory):
    """A mistuned 4-blade ring (5 %, seed 0, engine order 1) continued in omega from 240 rad/s round a fold (unstable
    past it; 60 points), with the CLI's reports for ``--state 'x*'``: ``(branch, JSON report, text report, plot
    path)``."""
    import contextlib
    import io

    from blademodel.cli import main
    from blademodel.orbits.branch_file import load_branch
    tmp = tmp_path_factory.mktemp("states")
    out, png = tmp / "b.nc", tmp / "b.png"
    args = ["continue", str(MODELS / "bladed_disk_24.yaml"), "--set", "blades=4", "--set", "engine_order=1", "--set",
            "mistuning_std=0.05", "--set", "mistuning_seed=0", "--param", "omega", "--from", "240", "--to", "300",
            "--max-points", "60", "--grazing-tol", "inf", "--state", "x*", "--out", str(out)]
    text = io.StringIO()
    with contextlib.redirect_stdout(text), contextlib.redirect_stderr(io.StringIO()):
        assert main(args + ["--plot", str(png)]) == 0
    report = io.StringIO()
    with contextlib.redirect_stdout(report), contextlib.redirect_stderr(io.StringIO()):
        assert main(args + ["--json"]) == 0   # read back from --out
    return load_branch(out), json.loads(report.getvalue()), text.getvalue(), png


def test_continue_with_a_pattern_reports_the_largest_blade_and_where_it_peaks(ring_branch):
    b, rep, text, png = ring_branch
    blades = [f"x{j}" for j in range(1, 5)]
    h = np.abs(b.harmonics[:, [b.state_names.index(x) for x in blades]])
    np.testing.assert_array_equal(rep["harmonic1"], h.max(axis=1))
    np.testing.assert_array_equal(rep["smallest1"], h.min(axis=1))
    assert rep["largest_state"] == [blades[j] for j in np.argmax(h, axis=1)]
    assert len(set(rep["largest_state"])) > 1   # the largest blade changes: the envelope is no one blade's curve
    k = int(np.argmax(h.max(axis=1)))
    assert (f"largest first harmonic of x*: {h[k].max():.6g} ({blades[int(np.argmax(h[k]))]}) at omega = "
            f"{b.params[k]:.8g} ({'stable' if b.stable[k] else 'unstable'})") in text
    if not b.stable[k]:   # the peak of what a run would settle on is given too
        j = int(np.argmax(np.where(b.stable, h.max(axis=1), -np.inf)))
        assert b.stable[j] and (f"; on the stable orbits {h[j].max():.6g} ({blades[int(np.argmax(h[j]))]}) at "
                                f"omega = {b.params[j]:.8g}") in text
    assert png.stat().st_size > 0


def test_the_plot_draws_the_largest_by_stability_and_the_smallest_thin(ring_branch):
    from blademodel.plots.branch import branch_figure
    b = ring_branch[0]
    h = np.abs(b.harmonics[:, [b.state_names.index(f"x{j}") for j in range(1, 5)]])
    ax = branch_figure(b, "x*").axes[0]
    thin = [ln for ln in ax.lines if ln.get_label() == "smallest of x*"]
    assert len(thin) == 1 and np.array_equal(thin[0].get_ydata(), h.min(axis=1))
    runs = [ln for ln in ax.lines if len(ln.get_xdata()) > 1 and ln.get_linewidth() == 1.6]   # in branch order
    starts = np.concatenate([ln.get_ydata()[:-1] for ln in runs])   # each segment's first point
    assert len(starts) == len(b.params) - 1
    np.testing.assert_array_equal(starts, h.max(axis=1)[:-1])
    dashed = [ln.get_linestyle() == "--" for ln in runs for _ in range(len(ln.get_xdata()) - 1)]
    assert dashed == [not (b.stable[k] and b.stable[k + 1]) for k in range(len(dashed))] and any(dashed)
    assert ax.get_ylabel() == "first-harmonic amplitude, largest of x*"
    from blademodel.plots.branch import CROWDED
    grazing = [ln for ln in ax.lines if ln.get_label() == "grazing"]
    count = sum(q.kind == "grazing" for q in b.special)
    assert len(grazing) == 1 and len(grazing[0].get_xdata()) == count
    assert grazing[0].get_markersize() == (3 if count > CROWDED else 7)   # many: small, the curve stays visible
    with pytest.raises(ValueError, match="the Poincare samples are drawn for one state"):
        branch_figure(b, "x*", quantity="section")


def test_plot_draws_a_branch_file_by_a_pattern_and_names_a_bad_one(ring_branch, tmp_path, capsys):
    from blademodel.cli import main
    nc = tmp_path / "copy.nc"
    nc.write_bytes(Path(ring_branch[3]).with_suffix(".nc").read_bytes())
    assert main(["plot", str(nc), "--state", "x*"]) == 0
    assert (tmp_path / "copy_branch.png").stat().st_size > 0
    assert main(["plot", str(nc), "--state", "q*"]) == 2
    assert "--state 'q*': the pattern matches no state of the model" in capsys.readouterr().err


def test_a_travelling_wave_s_blades_are_reported_alike_not_by_rounding_s_choice(tmp_path, capsys):
    """On a tuned ring's travelling wave every blade has the same first harmonic (to rounding): the report says so
    rather than naming the blade that rounding made largest, and the plot draws no smallest beside the largest."""
    from blademodel.cli import main
    from blademodel.orbits.branch_file import load_branch
    out = tmp_path / "wave.nc"
    assert main(["continue", str(MODELS / "bladed_disk_24.yaml"), "--set", "blades=4", "--set", "engine_order=1",
                 "--param", "omega", "--from", "280", "--to", "290", "--cyclic", "--max-points", "5",
                 "--grazing-tol", "inf", "--state", "x*", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    b = load_branch(out)
    h = np.abs(b.harmonics[:, [b.state_names.index(f"x{j}") for j in range(1, 5)]])
    assert np.all(h.max(axis=1) - h.min(axis=1) <= 1e-9 * h.max(axis=1))
    assert f"largest first harmonic of x*: {h.max():.6g} (all 4 alike) at omega = " in text
    from blademodel.plots.branch import branch_figure
    ax = branch_figure(b, "x*").axes[0]   # no second line for a smallest that is the largest
    assert not [ln for ln in ax.lines if "smallest" in ln.get_label()]
