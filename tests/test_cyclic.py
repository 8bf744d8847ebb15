"""The cyclic reduction of a tuned bladed disk: its travelling-wave orbits from a fraction of the period.

Checked against the whole ring's period map (its orbit, its run over the period, its
monodromy from the replayed tangent) and against difference quotients of the reduced
map; a continuation on the reduced map against the whole map's orbits and bifurcations.
"""

from pathlib import Path

import numpy as np
import pytest

from blademodel.config import BladedDisk, apply_overrides, load_config
from blademodel.numeric.kernels import make_integrator
from blademodel.orbits import continuation, find_periodic_orbit
from blademodel.orbits.cyclic import CyclicError, CyclicSymmetry
from blademodel.orbits.period_map import PeriodMap
MODELS = Path(__file__).resolve().parents[1] / "models"
SPP = 600


@pytest.mark.parametrize("friction, blades, engine_order, fraction, turn", [
    ("coulomb", 8, 3, 8, 3),    # T / 8, the ring turned by 3 blades (3 EO = 1 mod 8)
    ("bilinear", 6, 2, 3, 1),   # T / 3 (gcd 2), by 1 blade; the Jenkins sliders' states turn with their contacts
])
def test_the_reduced_map_gives_the_ring_s_orbit_its_run_over_the_period_and_its_monodromy(friction, blades,
                                                                                          engine_order, fraction,
                                                                                          turn):
    """The travelling-wave orbit that shooting finds on the whole ring's map is a fixed point of the reduced map;
    the reduced run rebuilds the whole period's; ``S^(-s d) J^d`` from the reduced map's tangent is the whole map's
    monodromy (the replayed tangents of two integrations, over ``T`` and over ``T / d``, in different
    roundings); the reduced map's tangent equals its difference quotients. Without the turn the reduced map does
    not hold the orbit. Taken as an orbit of two periods (``CyclicSymmetry(periods=2)``), the rebuilt run is the
    whole map's over ``2 T`` and ``(S^(-s d) J^d)^2`` its period-2 monodromy."""
    cfg = BladedDisk(blades=blades, engine_order=engine_order, friction=friction, omega=286.0)
    model = cfg.build()
    ig = make_integrator(model, steps_per_period=SPP)
    sym = CyclicSymmetry(cfg, ig)
    assert (sym.fraction, sym.turn) == (fraction, turn)
    orbit = find_periodic_orbit(model, integrator=ig, transient=50, jacobian="forward", workers=1)
    y, cm, size = orbit.state, orbit.mode, np.max(np.abs(orbit.state))
    whole, reduced = PeriodMap(ig, 1), PeriodMap(ig, 1, symmetry=sym)
    z, cz = reduced(y, cm.copy())
    assert np.max(np.abs(z - y)) <= 1e-10 * size and np.array_equal(cz, cm)
    unturned = reduced.run(y, cm.copy()).states[-1][:y.size]
    assert np.max(np.abs(unturned - y)) > 1e-3 * size
    rw, rr = whole.run(y, cm.copy()), reduced.run(y, cm.copy())
    assert rr.Y.shape[0] - 1 == (rw.Y.shape[0] - 1) // fraction and rr.period_orbit().shape == rw.Y.shape
    np.testing.assert_allclose(rr.period_orbit(), rw.Y, rtol=0, atol=1e-10 * np.max(np.abs(rw.Y)))
    M = whole.derivatives(y, cm.copy()).monodromy
    J = reduced.derivatives(y, cm.copy()).monodromy
    assert np.linalg.norm(sym.monodromy(J) - M) <= 1e-7 * np.linalg.norm(M)
    mu, mu_r = np.sort_complex(np.linalg.eigvals(M)), np.sort_complex(np.linalg.eigvals(sym.monodromy(J)))
    np.testing.assert_allclose(mu_r, mu, rtol=0, atol=1e-7)
    Jd = reduced.differences(y, cm.copy(), orbit.scale, rel_step=1e-5)
    S = orbit.scale[None, :] / orbit.scale[:, None]
    assert np.max(np.abs((Jd - J) * S)) <= 1e-5 * np.max(np.abs(J * S))
    # the same wave as an orbit of two periods: its run over 2 T and the monodromy of the period-2 map
    sym2 = CyclicSymmetry(cfg, ig, periods=2)
    assert sym.comes_back(y, orbit.scale) <= 1e-10 and sym2.comes_back(y, orbit.scale) <= 1e-10
    r2 = PeriodMap(ig, 1, symmetry=sym2).run(y, cm.copy())
    whole2 = PeriodMap(ig, 2)
    M2 = whole2.derivatives(y, cm.copy()).monodromy
    np.testing.assert_allclose(r2.period_orbit(), whole2.last_run.Y, rtol=0,
                               atol=1e-10 * np.max(np.abs(rw.Y)))
    assert np.linalg.norm(sym2.monodromy(J) - M2) <= 1e-7 * np.linalg.norm(M2)
    # the same wave on the map that keeps every k-th turn (G^k over k T / d, turned by k s blades): a fixed point
    # there too, its run the whole period's, its Jacobian J^k (the chain rule at a fixed point of G), and the
    # whole ring's monodromy from it
    k = 2 if fraction % 2 == 0 else 3
    sym_k = CyclicSymmetry(cfg, ig, every=k)
    assert (sym_k.fraction, sym_k.turn) == (fraction // k, (k * turn) % blades)
    Gk = PeriodMap(ig, 1, symmetry=sym_k)
    zk, czk = Gk(y, cm.copy())
    assert np.max(np.abs(zk - y)) <= 1e-10 * size and np.array_equal(czk, cm)
    np.testing.assert_allclose(Gk.run(y, cm.copy()).period_orbit(), rw.Y, rtol=0, atol=1e-10 * np.max(np.abs(rw.Y)))
    Jk = Gk.derivatives(y, cm.copy()).monodromy
    assert np.linalg.norm(Jk - np.linalg.matrix_power(J, k)) <= 1e-7 * np.linalg.norm(Jk)
    assert np.linalg.norm(sym_k.monodromy(Jk) - M) <= 1e-7 * np.linalg.norm(M)
    with pytest.raises(CyclicError, match=f"dividing N / gcd\\(EO, N\\) = {fraction}"):
        CyclicSymmetry(cfg, ig, every=fraction + 1)


def test_a_continuation_on_the_reduced_map_has_the_whole_map_s_orbits_and_bifurcations():
    """The tuned 24-blade ring (engine order 3: T / 8) from 273.8 to 275.6 rad/s on the reduced map and on the
    whole one: the same Neimark-Sacker point (to 1e-6 rad/s) and border collision (to 1e-5: each at a grazing
    located with a bracket, ``[274.2271501, 274.2271508]`` on the whole map, whose contacts graze one by one
    within 3e-6 rad/s there, ``[274.2271496, 274.2271536]`` on the reduced one, where they are one), every
    reduced branch point an orbit of the whole map (residual below 1e-8 of its scale) whose multipliers, from the
    whole map's tangent, are the branch's, and the events of the whole period counted."""
    cfg = load_config(MODELS / "bladed_disk_24.yaml")
    whole = continuation(cfg, "omega", 273.8, 275.6, workers=1)
    cyc = continuation(cfg, "omega", 273.8, 275.6, workers=1, cyclic=True)
    assert whole.message == cyc.message == "reached omega = 275.6"

    def kinds(b):
        return [(q.kind, q.param) for q in b.special if q.kind in ("border-collision", "neimark-sacker")]

    assert [k for k, _ in kinds(cyc)] == [k for k, _ in kinds(whole)] == ["border-collision", "neimark-sacker"]
    (_, bc), (_, ns) = kinds(cyc)
    (_, bc_whole), (_, ns_whole) = kinds(whole)
    assert abs(bc - bc_whole) <= 1e-5 and abs(ns - ns_whole) <= 1e-6
    scale = np.maximum(np.abs(cyc.states).max(axis=0), 1e-12)
    for k in range(0, cyc.params.size, max(cyc.params.size // 4, 1)):
        ig = make_integrator(apply_overrides(cfg, {"omega": float(cyc.params[k])}).build())
        P = PeriodMap(ig, 1)
        end, mode = P(cyc.states[k], cyc.modes[k].copy())
        assert np.max(np.abs(end - cyc.states[k]) / scale) <= 1e-8
        assert np.array_equal(mode, cyc.modes[k])
        mu = np.linalg.eigvals(P.derivatives(cyc.states[k], cyc.modes[k].copy()).monodromy)
        np.testing.assert_allclose(np.sort(np.abs(mu))[::-1][:6], np.sort(np.abs(cyc.multipliers[k]))[::-1][:6],
                                   rtol=0, atol=1e-7)
        assert cyc.events[k] == P.last_events


def test_a_preloaded_ring_whose_contacts_stick_in_chains_is_reduced_too():
    """The tuned 24-blade ring with every contact pressed (``gap = -1e-5`` m, Coulomb) at 250 rad/s: its stick
    chains form and break all round the ring, the closing contact's among them. The reduced map finds the orbit
    that shooting finds on the whole map (to 1e-9 of its scale), and every point the continuation on it gives is
    an orbit of the whole map in the same modes. (Until the stick factor wrote the zeros of other chains' entries,
    the closing chain read stale ones, the discrete flow lost the ring's symmetry by 4.7e-6 and ``cyclic=True``
    refused the ring.)"""
    cfg = apply_overrides(load_config(MODELS / "bladed_disk_24.yaml"), {"gap": -1e-5, "omega": 250.0})
    orbit = find_periodic_orbit(cfg.build(), transient=100, workers=1)
    cyc = continuation(cfg, "omega", 250.0, 250.5, workers=1, cyclic=True, transient=100)
    assert cyc.message == "reached omega = 250.5" and cyc.params.size >= 3
    assert np.max(np.abs(cyc.states[0] - orbit.state) / orbit.scale) <= 1e-9
    assert np.array_equal(cyc.modes[0], orbit.mode)
    for k in (0, cyc.params.size // 2, cyc.params.size - 1):
        assert _whole_map_residual(cfg, cyc, k) <= 1e-8


def _whole_map_residual(cfg, b, k) -> float:
    """Point ``k`` of branch ``b``: the scaled residual of its state under the whole period's map."""
    scale = np.maximum(np.abs(b.states).max(axis=0), 1e-12)
    ig = make_integrator(apply_overrides(cfg, {"omega": float(b.params[k])}).build())
    end, _ = PeriodMap(ig, 1)(b.states[k], b.modes[k].copy())
    return float(np.max(np.abs(end - b.states[k]) / scale))


def test_where_a_switching_time_passes_the_section_the_reduced_map_goes_on(monkeypatch):
    """At 292.725 rad/s three contacts of the tuned 24-blade ring (one a wave) open just as the reduced map's
    section passes (``1.7e-9 T / 8`` after it, and then before it): the branch's start modes change there from
    slip to open. Newton's iterates on either side of that switching time are settled
    (``ContactIntegrator.settle``), so the map is continuous across it and the reduced map steps over it
    alone; every point checked, on both sides, is an orbit of the whole map."""
    from blademodel.orbits import arclength as al
    parts = []
    segment = al._segment

    def recorded(*args, **kwargs):
        b = segment(*args, **kwargs)
        parts.append(kwargs["cyclic"])
        return b

    monkeypatch.setattr(al, "_segment", recorded)
    cfg = load_config(MODELS / "bladed_disk_24.yaml")
    b = continuation(cfg, "omega", 292.4, 293.2, workers=1, cyclic=True)
    assert b.message == "reached omega = 293.2" and parts == [True]
    changed = np.flatnonzero(b.modes[0] != b.modes[-1])
    assert changed.tolist() == [5, 13, 21] and (b.modes[-1][changed] == 0).all()
    k = int(np.flatnonzero((b.modes == b.modes[-1]).all(axis=1))[0])   # the first point past the switching
    assert b.params[k - 1] < 292.725 < b.params[k]
    for i in (0, k - 1, k, b.params.size - 1):
        assert _whole_map_residual(cfg, b, i) <= 1e-8


def test_where_the_reduced_map_stalls_the_whole_map_takes_the_branch_past_it(monkeypatch):
    """Where the reduced continuation stalls, the whole map takes the branch on for ten points, and the reduced
    map from there to the end, the message saying where. The stall is the one at 292.725 rad/s from before start
    states were settled (the start states left unsettled here). Each part resumes the last: every point is an
    orbit of the whole map."""
    from blademodel.numeric.contact_kernel import ContactIntegrator
    from blademodel.orbits import arclength as al
    monkeypatch.setattr(ContactIntegrator, "settle", lambda self, y, mode, t=0.0: (
        np.array(mode, dtype=np.int64).reshape(self.nc), []))
    parts = []
    segment = al._segment

    def recorded(*args, **kwargs):
        b = segment(*args, **kwargs)
        parts.append((kwargs["cyclic"], b.params.size, b.message))
        return b

    monkeypatch.setattr(al, "_segment", recorded)
    cfg = load_config(MODELS / "bladed_disk_24.yaml")
    b = continuation(cfg, "omega", 292.4, 293.2, workers=1, cyclic=True)
    assert b.message.startswith("reached omega = 293.2 (the cyclic reduction stalled at omega = 292.72")
    assert [c for c, _, _ in parts] == [True, False, True]
    assert parts[0][2].startswith(al.STALLED) and parts[1][1] == parts[0][1] + al.CYCLIC_FALLBACK_POINTS
    for k in (parts[0][1] - 1, parts[0][1] + 3, b.params.size - 1):
        assert _whole_map_residual(cfg, b, k) <= 1e-8


def test_a_stability_change_at_a_kink_crossed_by_a_short_step_is_a_border_collision():
    """Past its resonance the tuned ring's travelling waves change from 168 events a period to 216 (every contact
    grazes at once) at 1481.1533 rad/s, where the steps have shrunk to about 1e-5 rad/s: the leading multipliers
    jump from 1.40 to 0.95, the orbits from unstable to stable. The location's bracket closes to ``locate_tol``
    before it can narrow a thousandfold, and it was reported as a Neimark-Sacker point; the modulus still jumps by
    far more than a continuous multiplier changes over ``locate_tol``: a border collision, with its bracket."""
    cfg = load_config(MODELS / "bladed_disk_24.yaml")
    b = continuation(cfg, "omega", 1470.0, 1483.0, cyclic=True, grazing_tol=float("inf"), workers=1, transient=100)
    near = [q for q in b.special if q.kind != "grazing" and abs(q.param - 1481.1533) < 1e-3]
    assert [q.kind for q in near] == ["border-collision"] and near[0].bracket is not None
    lo, hi = near[0].bracket
    assert hi - lo < 1e-5
    before, after = b.params < lo, b.params > hi
    k0, k1 = np.nonzero(before)[0][-1], np.nonzero(after)[0][0]
    assert not b.stable[k0] and b.stable[k1] and b.events[k0] == 168 and b.events[k1] == 216
    assert np.max(np.abs(b.multipliers[k0])) - np.max(np.abs(b.multipliers[k1])) > 0.3


def test_where_the_steps_shrink_toward_a_kink_the_shots_past_it_take_the_field_s_steady_way():
    """Over 1480 to 2000 rad/s the tuned ring's steps shrink toward the kink at 1481.1533 rad/s until the
    corrections fail; the secant of the last two points then moves the field by only ``5e-4`` of its length (the
    scaled field is the range's), too little to tell its way, and the branch stalled there. The field's values had
    risen steadily: shooting just past them finds the orbit beyond the kink, and the branch goes on, through a
    border collision there (about 8 s)."""
    cfg = load_config(MODELS / "bladed_disk_24.yaml")
    b = continuation(cfg, "omega", 1480.0, 2000.0, cyclic=True, grazing_tol=float("inf"), workers=1, transient=100,
                     max_points=60)
    assert b.message.startswith("stopped after max_points = 60") and b.params[-1] > 1481.16
    assert [q.kind for q in b.special if q.kind != "grazing" and q.param < b.params[-1]] == ["border-collision"]
    assert np.all(np.diff(b.params) > 0)   # one way throughout: no turn was taken at the kink


@pytest.mark.slow
def test_a_whole_map_that_takes_over_a_stall_and_fails_at_once_ends_with_a_message(monkeypatch):
    """The tuned ring's reduced branch from 1250 rad/s stalled at 1481.15 while a secant that hardly moves the field
    gave no way to shoot in (that rule restored here); the whole map, resuming with the stalled point alone and the
    one before it as ``prior``, failed its first step too and, on an unstable orbit, looked for the stable arm of a
    nonsmooth fold from the last two points. That search read the second-to-last of the resumed points (there was
    one) and raised IndexError; it takes the trail with ``prior`` now, and the branch ends saying where and why
    (about 12 s)."""
    from blademodel.orbits import arclength as al

    def secant_only(ctx, pts, X):
        travel = X - ctx.unknowns(pts[-2])
        return float(np.sign(travel[-1])) if abs(travel[-1]) > 1e-3 * np.linalg.norm(travel) else 0.0
    monkeypatch.setattr(al, "_field_way", secant_only)
    cfg = load_config(MODELS / "bladed_disk_24.yaml")
    b = continuation(cfg, "omega", 1250.0, 2500.0, cyclic=True, grazing_tol=float("inf"), max_points=1500, workers=1)
    assert "the cyclic reduction stalled at omega = 1481.15" in b.message and b.message.startswith("the step fell")
    assert abs(b.params[-1] - 1481.15) < 0.01 and not b.stable[-1]


@pytest.mark.parametrize("values, field", [
    ({"mistuning_std": 0.02}, "mistuning"),
    ({"contacts": {2: {"mu": 0.3}}}, "contacts"),
    ({"engine_order": 8}, "engine_order"),
    ({"engine_order": 0}, "engine_order"),
])
def test_a_ring_without_the_symmetry_is_refused_naming_what_breaks_it(values, field):
    cfg = BladedDisk(**{"blades": 8, "engine_order": 3, "friction": "coulomb", "omega": 286.0, **values})
    ig = make_integrator(cfg.build(), steps_per_period=SPP)
    with pytest.raises(CyclicError, match=field):
        CyclicSymmetry(cfg, ig)


def test_the_reduced_map_needs_whole_steps_and_a_ring():
    cfg = BladedDisk(blades=8, engine_order=3, friction="coulomb", omega=286.0)
    with pytest.raises(CyclicError, match="steps_per_period = 1001"):
        CyclicSymmetry(cfg, make_integrator(cfg.build(), steps_per_period=1001))
    from blademodel.zheng2022 import BladePair
    with pytest.raises(CyclicError, match="bladed disk"):
        continuation(BladePair(), "omega", 280.0, 281.0, cyclic=True)


def test_the_continue_command_with_cyclic(tmp_path, capsys):
    """``blademodel continue --cyclic``: the branch on the reduced map, saved and reported as any (its events of
    the whole period); without it, a tuned ring gets a hint that it may be used (a mistuned one a hint on
    ``--grazing-tol`` instead, unless that is given); refused on a mistuned ring (exit code 2, naming the field);
    taken with ``--switch`` (whose branches run on the whole map:
    ``test_a_period_doubling_found_on_the_reduced_map_is_switched_on_the_whole_one``)."""
    import json

    from blademodel.cli import main
    from blademodel.orbits.branch_file import load_branch
    yaml = str(MODELS / "bladed_disk_24.yaml")
    out = tmp_path / "ring.nc"
    assert main(["continue", yaml, "--param", "omega", "--from", "280", "--to", "280.4", "--cyclic", "--json",
                 "--out", str(out), "--workers", "1"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["message"] == "reached omega = 280.4"
    assert main(["continue", yaml, "--param", "omega", "--from", "280", "--to", "280.05", "--workers", "1"]) == 0
    assert "hint: this ring is tuned and driven in engine order: --cyclic follows its travelling waves on T / 8" \
        in capsys.readouterr().err
    b = load_branch(out)
    ig = make_integrator(apply_overrides(load_config(MODELS / "bladed_disk_24.yaml"), {"omega": 280.0}).build())
    P = PeriodMap(ig, 1)
    end, _ = P(b.states[0], b.modes[0].copy())
    assert np.max(np.abs(end - b.states[0])) <= 1e-8 * np.max(np.abs(b.states[0]))
    assert b.events[0] == P.last_events
    assert main(["continue", yaml, "--param", "omega", "--from", "280", "--to", "280.4", "--cyclic",
                 "--set", "mistuning_std=0.02"]) == 2
    assert "mistuning" in capsys.readouterr().err
    assert main(["continue", yaml, "--param", "omega", "--from", "280", "--to", "280.05", "--workers", "1",
                 "--set", "mistuning_std=0.02", "--max-points", "3"]) == 0
    err = capsys.readouterr().err
    assert "--cyclic" not in err and "hint: the blades or contacts of this ring differ" in err   # not the cyclic hint
    assert main(["continue", yaml, "--param", "omega", "--from", "280", "--to", "280.05", "--workers", "1",
                 "--set", "mistuning_std=0.02", "--max-points", "3", "--grazing-tol", "inf"]) == 0
    assert "hint" not in capsys.readouterr().err   # its grazing points' tolerance given: no hint
    assert main(["continue", yaml, "--param", "omega", "--from", "280", "--to", "280.4", "--cyclic", "--switch",
                 "--json", "--workers", "1"]) == 0   # no period doubling here: nothing to switch to, and no refusal
    assert json.loads(capsys.readouterr().out)["message"] == "reached omega = 280.4"


@pytest.mark.slow
def test_a_period_doubling_of_the_96_blade_ring_is_followed_on_the_reduced_map():
    """The tuned 96-blade ring (engine order 12: T / 8, a turn by 1 blade, ``S = 600``) has a period doubling near
    272.27 rad/s where the reduced map has a branch point (``J`` with the eigenvalue +1). Its doubled orbits come
    back after one period turned by ``s d = 8`` blades, ``Phi_T(y) = S^(-8) y``, and are fixed points of the
    reduced map: the doubled branch followed there takes the same values of the field as on the whole ring's
    period-2 map (to 1e-6 rad/s), and each point is an orbit of the whole period-2 map (residual below 1e-8) and
    not of the period-1 map, with the multipliers of the whole period-2 map's monodromy, its amplitudes over
    ``2 T`` and its events. Resumed with ``periods=2, cyclic=True`` (as ``blademodel continue --cyclic --switch``
    resumes an unfinished doubled branch), it goes on on the reduced map from its last point."""
    from blademodel.orbits import period_doubled_branch
    cfg = apply_overrides(load_config(MODELS / "bladed_disk_24.yaml"), {"blades": "96", "engine_order": "12"})
    b = continuation(cfg, "omega", 272.0, 272.6, workers=1, cyclic=True, steps_per_period=600)
    (pd,) = b.points("period-doubling")
    kw = dict(steps_per_period=600, workers=1, max_points=4)
    d = period_doubled_branch(cfg, "omega", pd, 271.5, 273.0, cyclic=True, **kw)
    whole = period_doubled_branch(cfg, "omega", pd, 271.5, 273.0, **kw)
    assert "whole ring's map" not in d.message and d.periods == whole.periods == 2
    np.testing.assert_allclose(d.params, whole.params, rtol=0, atol=1e-6)
    assert d.params[0] == pd.param and np.allclose(d.states[0], pd.state)
    scale = np.maximum(np.abs(d.states).max(axis=0), 1e-12)
    for k in range(1, d.params.size):
        ig = make_integrator(apply_overrides(cfg, {"omega": float(d.params[k])}).build(), steps_per_period=600)
        y, m = d.states[k], d.modes[k]
        P2 = PeriodMap(ig, 2)
        s = P2.derivatives(y, m.copy())
        end1, _ = PeriodMap(ig, 1)(y, m.copy())
        assert np.max(np.abs(s.state - y) / scale) <= 1e-8 and np.max(np.abs(end1 - y) / scale) > 1e-3
        turn = CyclicSymmetry(cfg, ig).monodromy(np.eye(y.size))   # S^(-s d)
        assert np.max(np.abs(end1 - turn @ y) / scale) <= 1e-8
        mu = np.sort(np.abs(np.linalg.eigvals(s.monodromy)))[::-1][:6]
        np.testing.assert_allclose(mu, np.sort(np.abs(d.multipliers[k]))[::-1][:6], rtol=0, atol=1e-6)
        Y = P2.last_run.Y
        np.testing.assert_allclose(d.amplitudes[k], 0.5 * (Y.max(axis=0) - Y.min(axis=0)), rtol=1e-7,
                                   atol=1e-9 * np.max(np.abs(Y)))
        assert d.events[k] == P2.last_events
    # resumed (as blademodel continue resumes an unfinished doubled branch), on the reduced map again
    more = continuation(cfg, "omega", 271.5, 273.0, periods=2, cyclic=True, resume=d, **{**kw, "max_points": 6})
    assert more.params.size > d.params.size and np.array_equal(more.params[:d.params.size], d.params)
    ig = make_integrator(apply_overrides(cfg, {"omega": float(more.params[-1])}).build(), steps_per_period=600)
    end2, _ = PeriodMap(ig, 2)(more.states[-1], more.modes[-1].copy())
    assert np.max(np.abs(end2 - more.states[-1]) / scale) <= 1e-8


@pytest.mark.slow
def test_a_period_doubling_bubble_ends_where_it_comes_back_to_the_period_1_waves():
    """The tuned 32-blade ring at engine order 4 (``T / 8`` again, as the 96-blade one at 12) doubles at 272.2745
    and 275.7428 rad/s; the branch doubled at the first, on the reduced map and given its parent, swells into a loop
    and ends at the second: its last points approach it in the field, and their orbits collapse onto period 1 (the
    whole ring's one-period residual falls to a small fraction of its size inside the bubble), where before it went
    on round the same orbits a period later until the self-overlap check stopped it."""
    from blademodel.orbits import period_doubled_branch
    cfg = apply_overrides(load_config(MODELS / "bladed_disk_24.yaml"), {"blades": "32", "engine_order": "4"})
    b = continuation(cfg, "omega", 271.5, 276.5, workers=1, cyclic=True, steps_per_period=SPP)
    first, *_, last = b.points("period-doubling")
    d = period_doubled_branch(cfg, "omega", first, 271.5, 276.5, workers=1, cyclic=True, steps_per_period=SPP,
                              parent=b)
    assert d.message.startswith(f"came back to the period-1 orbits at their period doubling omega = {last.param:.6g}")
    assert abs(d.params[-2] - last.param) < 1e-2 and d.params.max() < last.param + 1e-2
    ig = make_integrator(cfg.build(), steps_per_period=SPP)

    def one_period_off(j):   # how far the orbit at point j is from period 1
        P = PeriodMap(ig.with_parameters(apply_overrides(cfg, {"omega": str(d.params[j])}).build()), 1)
        y = d.states[j]
        z = np.zeros(ig.n_state)
        z[:y.size] = y
        return float(np.max(np.abs(P(y.copy(), ig.mode_of(z))[0] - y)))
    inside = one_period_off(int(np.argmin(np.abs(d.params - 274.0))))
    assert one_period_off(d.params.size - 2) < 0.2 * inside
