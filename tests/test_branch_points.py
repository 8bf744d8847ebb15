"""Branch points: a multiplier through ``+1`` where the branch goes on (another branch crosses it), told from a fold,
and the switch onto the crossing branch (``branch_point_branch``).

The model is ``models/twin_blades_stops.yaml``: two identical blades, each against a gapped stop, coupled by a
spring and driven alike. Its blades can move alike (``x1 = x2``), and orbits that break that symmetry cross the
symmetric branch at its branch points.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from blademodel.config import apply_overrides, load_config
from blademodel.numeric.kernels import make_integrator
from blademodel.orbits import PeriodMap, branch_point_branch, continuation

YAML = Path(__file__).resolve().parent.parent / "models" / "twin_blades_stops.yaml"
MIRROR = [1, 0, 3, 2]   # the state (x1, x2, vx1, vx2) with the blades swapped


@pytest.fixture(scope="module")
def symmetric():
    """The branch of orbits with the blades alike, from 900 to 2200 rad/s (from rest at 900)."""
    cfg = load_config(YAML)
    return cfg, continuation(cfg, "omega", 900.0, 2200.0, workers=1)


def _map(cfg, omega, y):
    """The period map at ``omega`` (built afresh, differentiated by differences) and the contact modes of ``y``."""
    P = PeriodMap(make_integrator(apply_overrides(cfg, {"omega": str(omega)}).build()), 1, "differences", 1)
    full = np.zeros(P.integrator.n_state)
    full[:y.size] = y
    return P, P.integrator.mode_of(full)


def _scale(states):
    """Each state's scale: the largest displacement (velocity) of either blade on the branch's section states."""
    x, v = np.max(np.abs(states[:, :2])), np.max(np.abs(states[:, 2:]))
    return np.array([x, x, v, v])


def test_a_multiplier_through_one_is_a_fold_where_the_branch_turns_and_a_branch_point_where_it_goes_on(symmetric):
    """On the symmetric branch a real multiplier passes ``+1`` four times. At 1646.68 and 1283.16 rad/s the branch
    turns back (the field is extreme there among the branch's points): folds, whose critical eigenvector keeps the
    symmetry. At 1639.45 and just past the lower fold it goes on through (the field monotonic across): branch
    points, whose critical eigenvector reverses the symmetry (the blades move oppositely), as the mode that
    breaks it must. Every orbit of the branch is symmetric (to the orbits' tolerance)."""
    cfg, b = symmetric
    assert np.max(np.abs(b.states - b.states[:, MIRROR]) / _scale(b.states)) < 1e-9
    plus_one = [q for q in b.special if q.kind in ("fold", "branch-point")]
    assert [q.kind for q in plus_one] == ["fold", "branch-point", "fold", "branch-point"]
    for q in plus_one:
        i = q.index
        # (the lower fold and branch point lie 1e-3 rad/s apart, each with a multiplier near 1: located to 1e-4)
        assert abs(q.multiplier - 1.0) < (1e-6 if q.param > 1500 else 1e-3)
        around = b.params[i - 2:i + 4] if q.kind == "fold" else b.params[i:i + 3]   # (the lower pair: 1e-3 apart)
        steps = np.sign(np.diff(around))
        turns = bool(np.any(steps != steps[0]))
        assert turns == (q.kind == "fold"), (q.kind, q.param, around)
        if q.kind == "fold":   # the field's extreme
            assert q.param >= around.max() or q.param <= around.min()
        else:
            assert min(b.params[i], b.params[i + 1]) <= q.param <= max(b.params[i], b.params[i + 1])
        y = np.asarray(q.state)
        scale = _scale(b.states)
        P, mode = _map(cfg, q.param, y)
        J = P.jacobian(y, mode, scale, 1e-6)
        lam, W = np.linalg.eig(J)
        k = int(np.argmin(np.abs(lam - 1.0)))
        v = np.real(W[:, k]) / scale
        v /= np.max(np.abs(v))
        sign = -1.0 if q.kind == "branch-point" else 1.0
        assert np.max(np.abs(v - sign * v[MIRROR])) < 1e-5, (q.kind, v)


def test_the_switch_at_a_branch_point_follows_orbits_that_break_the_symmetry(symmetric):
    """From the branch point just above the lower fold, the switch leaves the symmetric orbits: the new branch's
    first point is the branch point, every later one has the blades moving differently, and each is an orbit of a
    freshly built map, as is its mirror image (the blades swapped). Its stable orbits, one blade on its stop and
    the other hardly moving (localised), are found again by a long integration from a start displaced from them."""
    cfg, b = symmetric
    bp = b.points("branch-point")[-1]
    nb = branch_point_branch(cfg, "omega", bp, 1280.0, 1700.0, workers=1, max_points=120)
    assert nb.params[0] == bp.param and nb.periods == 1
    scale = _scale(nb.states)
    asym = np.max(np.abs(nb.states - nb.states[:, MIRROR]) / scale, axis=1)
    assert asym[0] < 1e-9 and np.all(asym[1:] > 1e-3) and asym[-1] > 0.5, asym[:4]
    for j in range(1, nb.params.size, 17):
        for y in (nb.states[j], nb.states[j][MIRROR]):
            P, mode = _map(cfg, nb.params[j], y)
            Py, _ = P(y.copy(), mode)
            assert np.max(np.abs(Py - y) / scale) < 1e-9
    stable = np.nonzero(nb.stable[1:])[0] + 1
    assert stable.size > 10
    j = int(stable[stable.size // 2])
    y, w = nb.states[j], nb.params[j]
    amp = np.abs(nb.harmonics[j, :2])
    assert max(amp) > 10 * min(amp)   # localised
    ig = make_integrator(apply_overrides(cfg, {"omega": str(w)}).build())
    z = np.zeros(ig.n_state)
    z[:y.size] = y * (1.0 + 1e-3 * np.array([1.0, -2.0, 1.5, -1.0]))
    mode = ig.mode_of(z)
    status, mode, _ = ig.advance(z, mode, 0, 1500)
    assert status == 0 and np.max(np.abs(z[:y.size] - y) / scale) < 1e-8


def test_the_switch_is_refused_at_a_point_of_another_kind(symmetric):
    cfg, b = symmetric
    with pytest.raises(ValueError, match="must be a branch point, got a 'fold' point"):
        branch_point_branch(cfg, "omega", b.points("fold")[0], 900.0, 2200.0)
    with pytest.raises(ValueError, match="lies outside"):
        branch_point_branch(cfg, "omega", b.points("branch-point")[0], 1700.0, 2200.0)


def test_continue_switches_at_branch_points(tmp_path, capsys):
    """``blademodel continue --switch`` follows the crossing branch at each branch point, saved beside ``--out``;
    the report's crossing branches start at the branch points, their orbits break the symmetry, and each ends
    where it meets the branch it crossed again, at the other branch point."""
    from blademodel.cli import main
    from blademodel.orbits.branch_file import load_branch
    out = tmp_path / "twin.nc"
    assert main(["continue", str(YAML), "--param", "omega", "--from", "900", "--to", "2200", "--json",
                 "--switch", "--out", str(out)]) == 0
    rep = json.loads(capsys.readouterr().out)
    bps = [p["value"] for p in rep["special"] if p["kind"] == "branch-point"]
    assert len(bps) == len(rep["branched"]) == 2
    for k, at in enumerate(bps):
        crossing = load_branch(tmp_path / f"twin_bp{k + 1}.nc")
        assert crossing.params[0] == at == rep["branched"][k]["values"][0]
        # each ends where it comes back to the other branch point (the loop joins them), not going round it again
        other = bps[1 - k]
        assert crossing.message.startswith(f"met the branch it crossed again at its branch point omega = {other:.6g}")
        assert abs(crossing.params[-2] - other) < 1e-3 * (2200 - 900)
        asym = np.max(np.abs(crossing.states - crossing.states[:, MIRROR]) / _scale(crossing.states), axis=1)
        assert asym[0] < 1e-9 and asym.max() > 0.5   # (it comes back to the symmetric orbits at the other one)


@pytest.mark.slow
def test_a_tuned_ring_s_travelling_wave_gives_way_between_two_branch_points():
    """The tuned 24-blade Coulomb ring (``models/bladed_disk_24.yaml``) driven twice as hard (``F0 = 120`` N), on
    the cyclic reduction from 315 to 330 rad/s: a multiplier of the whole ring passes ``+1`` at about 319.69 and
    324.98 rad/s while the reduced branch goes on through (no fold): two branch points, the travelling wave
    unstable between them. The switch at the first follows orbits that are no travelling waves (turned by one
    blade and shifted by ``T / 8`` they differ from themselves) but keep the turn by two blades and ``T / 4``, and
    the switch with ``cyclic`` follows them on the map over ``T / 4`` that keeps that turn, to the same orbits,
    and ends where they come back to the travelling waves, at the other branch point;
    an integration from rest at such an orbit's value of omega settles on it, its blades' first harmonics (sorted)
    equal to the orbit's, where the wave is unstable: the ring's steady state there."""
    cfg = apply_overrides(load_config(YAML.parent / "bladed_disk_24.yaml"), {"F0": "120"})
    b = continuation(cfg, "omega", 315.0, 330.0, workers=1, cyclic=True)
    bps = b.points("branch-point")
    assert len(bps) == 2 and not b.points("fold") and 319 < bps[0].param < 320.5 and 324.5 < bps[1].param < 325.5
    for q in bps:
        assert np.all(np.diff(b.params[q.index - 2:q.index + 4]) > 0)   # the reduced branch goes on
    inside = (b.params > bps[0].param) & (b.params < bps[1].param)
    assert not np.any(b.stable[inside])
    nb = branch_point_branch(cfg, "omega", bps[0], 315.0, 330.0, workers=1, max_points=12)
    # on the map over T / 4 turned by two blades (the reduced map period-doubles at the branch point): the same orbits
    reduced = branch_point_branch(cfg, "omega", bps[0], 315.0, 330.0, workers=1, max_points=12, cyclic=True)
    assert "whole ring" not in reduced.message and "whole ring" not in nb.message
    # (compared as orbits, not point by point: the two step controls see the same curve through other rounding,
    # and their points drift apart by 3e-2 rad/s within 12 points on one machine, agreeing to 1e-5 on another)
    scale = np.max(np.abs(nb.states), axis=0)
    for w, y, mode in zip(reduced.params[1:], reduced.states[1:], reduced.modes[1:]):
        P, _ = _map(cfg, w, y)
        assert np.max(np.abs(P(y, np.array(mode, dtype=np.int64))[0] - y) / scale) < 1e-8   # an orbit of the ring
    k = int(np.argmin(np.abs(reduced.params - nb.params[6])))
    w = float(reduced.params[k])
    j = int(np.argmin(np.abs(nb.params - w)))
    from blademodel.orbits import find_periodic_orbit
    whole = find_periodic_orbit(apply_overrides(cfg, {"omega": str(w)}).build(), guess=nb.states[j],
                                mode=nb.modes[j], transient=0, workers=1)
    # the same orbit up to which blade it is centred on (the crossing orbits break the travelling wave, and each
    # turn of one is another of them): the blades' first harmonics, sorted
    xs = [i for i, name in enumerate(nb.state_names) if name.startswith("x")]
    found = np.sort(np.abs([whole.harmonic(nb.state_names[i]) for i in xs]))
    assert np.max(np.abs(found - np.sort(np.abs(reduced.harmonics[k, xs])))) < 1e-6 * found[-1]
    assert found[-1] - found[0] > 1e-4 * found[-1]   # (which would tell one blade from another)
    assert reduced.integrations < nb.integrations
    # followed on, the crossing branch ends where it passes the travelling waves again: at the other branch point
    on = branch_point_branch(cfg, "omega", bps[0], 315.0, 330.0, workers=1, cyclic=True)
    assert on.message.startswith("came back to the travelling waves near omega = ")
    # (the vertex of the parabola through the last two points: the step turned across it)
    assert abs(float(on.message.split("= ")[1].split(",")[0]) - bps[1].param) < 2e-3 and on.params.size < 40
    j = int(np.nonzero(nb.stable)[0][-1])
    w, y = nb.params[j], nb.states[j]
    assert bps[0].param < w < bps[1].param
    ig = make_integrator(apply_overrides(cfg, {"omega": str(w)}).build())
    from blademodel.orbits.cyclic import CyclicSymmetry
    sym = CyclicSymmetry(cfg, ig)
    S, d = ig.steps_per_period, sym.fraction
    z = np.zeros(ig.n_state)
    z[:y.size] = y
    rec = ig.record_buffer(S + 1)
    # from the branch's own mode: the section state may lie on a switching boundary, where the mode the state
    # alone reads is the other side's (measured on one machine: the turn by two blades then off by 2.5e-6)
    ig.advance(z, np.array(nb.modes[j], dtype=np.int64), 0, 1, n_transient=0, record=rec)
    Y = rec[1][:, :sym.n]
    scale = np.max(np.abs(Y), axis=0)

    def turned(k):   # the orbit at k T / d, turned back by k s blades: equal to its start where it has that symmetry
        yk = Y[k * S // d]
        for _ in range(k):
            yk = sym.turned(yk)
        return float(np.max(np.abs(yk - Y[0]) / scale))
    assert turned(1) > 1e-2 and turned(2) < 1e-9
    xs = [i for i, name in enumerate(nb.state_names) if name.startswith("x")]
    orbit = np.sort(np.abs(nb.harmonics[j, xs]))
    assert orbit[-1] - orbit[0] > 1e-4 * orbit[-1]          # the blades' amplitudes differ
    z = np.zeros(ig.n_state)
    status, mode, _ = ig.advance(z, ig.mode_of(z), 0, 300)
    assert status == 0
    rec = ig.record_buffer(S + 1)
    ig.advance(z, mode, 0, 1, n_transient=0, record=rec)
    X = rec[1][:-1][:, xs]
    settled = np.sort(np.abs(2 * np.fft.rfft(X, axis=0)[1] / X.shape[0]))
    assert np.max(np.abs(settled - orbit)) < 1e-9 * orbit[-1]


@pytest.mark.slow
def test_continue_cyclic_switches_at_a_ring_s_branch_points(capsys):
    """``blademodel continue --cyclic --switch`` on the ring of the test above: each crossing branch is followed on
    the map over ``T / 4`` (its message names no whole map) and ends at the other branch point."""
    from blademodel.cli import main
    assert main(["continue", str(YAML.parent / "bladed_disk_24.yaml"), "--set", "F0=120", "--param", "omega",
                 "--from", "315", "--to", "330", "--cyclic", "--switch", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    bps = [p["value"] for p in rep["special"] if p["kind"] == "branch-point"]
    assert len(bps) == len(rep["branched"]) == 2
    for k, crossing in enumerate(rep["branched"]):
        assert crossing["values"][0] == bps[k] and "whole ring" not in crossing["message"]
        assert crossing["message"].startswith((f"came back to the travelling waves at their branch point omega = "
                                               f"{bps[1 - k]:.6g}", "met the branch it crossed"))
        assert abs(crossing["values"][-2] - bps[1 - k]) < 0.1
