"""Periodic orbits by shooting: exact linear responses, long integrations, Lyapunov exponents, unstable orbits."""

import numpy as np
import pytest
from scipy.linalg import expm

from blademodel.analysis.lyapunov import largest_lyapunov
from blademodel.config import BladedDisk
from blademodel.zheng2022 import BladePair
from blademodel.numeric import simulate
from blademodel.numeric.kernels import make_integrator
from blademodel.orbits import PeriodMap, ShootingError, find_periodic_orbit
from linear_reference import forced_response, linear_parts


def test_a_contact_free_orbit_is_the_exact_forced_response():
    """Gap out of reach: the orbit is ``Re(Y exp(i w t))`` with ``(i w - A) Y = b_c - i b_s`` (RK8, S = 1000),
    its first harmonics are ``Y``, and its multipliers those of ``expm(A T)``."""
    m = BladePair(gap=1.0).build()
    ig = make_integrator(m, steps_per_period=1000, method="rk8")
    o = find_periodic_orbit(m, integrator=ig, transient=0)
    A = linear_parts(ig)[0]
    Y = forced_response(ig)
    assert np.max(np.abs(o.state - Y.real) / o.scale) < 1e-8
    for i, name in enumerate(o.state_names):
        assert abs(o.harmonic(name) - Y[i]) < 1e-8 * np.max(np.abs(Y[i % 4::4]))
    exact = np.linalg.eigvals(expm(A * ig.period))
    gaps = np.abs(o.multipliers[:, None] - exact[None, :])   # each one near one of the other set (pairs repeat)
    assert gaps.min(axis=0).max() < 1e-7 and gaps.min(axis=1).max() < 1e-7
    assert o.stable and len(o.history) <= 3


@pytest.mark.parametrize("law", ["coulomb", "bilinear"])
def test_the_orbit_is_where_a_long_integration_settles(law):
    """From two periods after rest Newton converges (quadratically) to the Poincare sample of a 400-period run."""
    m = BladePair(friction=law).build()
    o = find_periodic_orbit(m, transient=1)
    assert o.residual <= 1e-10 and len(o.history) <= 5
    steps = [(a, b) for a, b in zip(o.history, o.history[1:]) if a > 1e-6]
    assert steps and all(b < 10 * a ** 2 for a, b in steps)   # quadratic, down to the differences' floor
    r = simulate(m, transient=400, periods=1)
    assert np.max(np.abs(r.poincare[-1][:o.state.size] - o.state) / o.scale) < 1e-9
    assert o.stable


def test_the_largest_multiplier_gives_the_lyapunov_exponent():
    """A stable orbit's largest Lyapunov exponent is ``ln |mu_1|`` per period (two-trajectory estimate, 2000 periods)."""
    m = BladePair(friction="bilinear").build()
    ig = make_integrator(m)
    o = find_periodic_orbit(m, integrator=ig)
    lam = largest_lyapunov(ig, o.state, o.mode, start_period=0, periods=2000, scale=o.scale)
    mu1 = np.log(abs(o.largest_multiplier))
    assert abs(lam - mu1) < 1e-3 * abs(mu1)


def test_an_unstable_orbit_inside_chaos():
    """Bilinear pair at gamma = 10 (chaotic): shooting from Poincare samples of the attractor finds a period-1
    orbit that no forward integration settles on. It is a fixed point of the map to the tolerance, its largest
    multiplier lies outside the unit circle, and a small displacement along that multiplier's eigenvector grows
    by that multiplier each period, integrated independently of the difference quotients."""
    m = BladePair(friction="bilinear", gamma=10.0).build()
    ig = make_integrator(m)
    r = simulate(m, transient=100, periods=4)
    o = None
    for y in r.poincare:
        try:
            o = find_periodic_orbit(m, integrator=ig, guess=y, transient=0, max_iter=15)
            break
        except ShootingError:
            continue
    assert o is not None and o.residual <= 1e-10
    mu = o.largest_multiplier
    assert abs(mu) > 1.5 and not o.stable
    assert abs(mu.imag) < 1e-9 * abs(mu)            # a real multiplier here (a saddle)
    v = np.real(np.linalg.eig(o.monodromy)[1][:, 0])
    P = PeriodMap(ig, 1)
    eps = 1e-7
    y, mode = o.state + eps * v / np.max(np.abs(v / o.scale)), o.mode
    d0 = (y - o.state) / o.scale
    growth = []
    for _ in range(3):
        y, mode = P(y, mode)
        d = (y - o.state) / o.scale
        growth.append(np.dot(d, d0) / np.dot(d0, d0))
        d0 = d
    assert np.allclose(growth, mu.real, rtol=1e-3)


def test_an_orbit_of_a_mistuned_ring():
    """The per-contact kernel (contact modes as an array): a 4-blade mistuned ring's orbit equals a long run's
    Poincare sample."""
    m = BladedDisk(blades=4, engine_order=1, friction="coulomb", mistuning=[0, 0.03, -0.02, 0.01]).build()
    o = find_periodic_orbit(m, transient=5)
    r = simulate(m, transient=300, periods=1)
    assert isinstance(o.mode, np.ndarray) and o.mode.shape == (4,)
    assert np.max(np.abs(r.poincare[-1][:o.state.size] - o.state) / o.scale) < 1e-9 and o.stable


def test_a_continuation_integrates_each_run_once(monkeypatch):
    """A run that logs more events than the map's event log holds is integrated again with room for them, and the
    map keeps the larger log. A continuation makes a map at each new value of its field; these start from the size
    their predecessors learned. Before, each started at 64 entries, and on a mistuned 24-blade ring (about 170
    events a period) each first run at a new value was integrated twice: 239 runs of the kernel for the 124
    integrations of this branch. Now the extra runs are only the first map's and the first orbit's shooting."""
    from pathlib import Path

    from blademodel.config import apply_overrides, load_config
    from blademodel.numeric import contact_kernel
    from blademodel.orbits import continuation
    runs = []
    advance = contact_kernel.ContactIntegrator.advance

    def counted(self, *args, **kwargs):
        runs.append(1)
        return advance(self, *args, **kwargs)

    monkeypatch.setattr(contact_kernel.ContactIntegrator, "advance", counted)
    cfg = apply_overrides(load_config(Path(__file__).resolve().parents[1] / "models" / "bladed_disk_24.yaml"),
                          {"mistuning_std": 0.02, "mistuning_seed": 1})
    b = continuation(cfg, "omega", 1300, 1320, grazing_tol=float("inf"), workers=1)
    assert b.message == "reached omega = 1320" and b.integrations >= 100
    assert len(runs) - b.integrations <= 0.1 * b.integrations


def test_no_convergence_is_an_error_with_the_history():
    with pytest.raises(ShootingError, match="did not converge in 1 Newton steps") as err:
        find_periodic_orbit(BladePair(friction="bilinear").build(), transient=0, max_iter=1)
    assert len(err.value.history) == 2 and err.value.history[-1] > 1e-10


def test_periods_must_be_positive():
    with pytest.raises(ValueError, match="periods"):
        find_periodic_orbit(BladePair().build(), periods=0)


def test_the_orbit_command(capsys):
    """``blademodel orbit MODEL.yaml --json``: the same orbit as the Python call; bad settings exit 2."""
    import json
    from pathlib import Path

    from blademodel.cli import main
    yaml = str(Path(__file__).resolve().parent.parent / "models" / "blade_pair_coulomb.yaml")
    assert main(["orbit", yaml, "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    o = find_periodic_orbit(BladePair(friction="coulomb").build())
    assert np.allclose([rep["state"][n] for n in o.state_names], o.state, rtol=0, atol=1e-12)
    assert rep["stable"] is True and abs(rep["multipliers"][0]["abs"] - abs(o.multipliers[0])) < 1e-9
    assert main(["orbit", yaml, "--periods", "0"]) == 2
    assert "--periods must be at least 1" in capsys.readouterr().err


def test_a_tolerance_below_rounding_is_named_as_such(capsys):
    """Asked for a residual below what the arithmetic gives (the bilinear pair's orbits stall between 9e-14 and
    8e-13), shooting and continuation say that ``tol`` is what stops them and what tolerance to take, not that the
    start is far from an orbit or that more steps a period may get through; a start far from any orbit (the chaotic
    pair at gamma = 10, two Newton steps) is not put down to rounding."""
    from blademodel.orbits import continuation
    cfg = BladePair(friction="bilinear")
    with pytest.raises(ShootingError) as e:
        find_periodic_orbit(cfg.build(), tol=1e-15)
    assert e.value.least_tol is not None and 1e-13 <= e.value.least_tol <= 1e-10
    assert min(e.value.history) < e.value.least_tol and "rounding errors" in str(e.value)
    with pytest.raises(ShootingError) as e:
        find_periodic_orbit(BladePair(friction="bilinear", gamma=10).build(), transient=3, max_iter=2)
    assert e.value.least_tol is None and "rounding" not in str(e.value)
    # a branch whose corrections ask for less than rounding gives, past a first orbit found to a tolerance it gives
    # (where the residuals stall between 9e-14 and 1.2e-12 rounding decides, so tol is set below them all)
    from blademodel.orbits import corrector
    init = corrector._Context.__init__
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(corrector._Context, "__init__",
                   lambda self, fam, scale, span, tol, *args: init(self, fam, scale, span, 1e-15, *args))
        b = continuation(cfg, "omega", 280, 280.02, tol=1e-10, workers=1)
    assert b.params[-1] < 280.02 and "take tol (--tol)" in b.message and "steps_per_period" not in b.message
    with pytest.raises(ShootingError) as e:
        continuation(cfg, "omega", 280, 281, tol=1e-15, workers=1)
    assert e.value.least_tol is not None and "far from such an orbit" not in str(e.value)
    from pathlib import Path

    from blademodel.cli import main
    yaml = str(Path(__file__).resolve().parent.parent / "models" / "blade_pair_bilinear.yaml")
    for command in (["orbit", yaml], ["continue", yaml, "--param", "omega", "--from", "280", "--to", "281"]):
        assert main(command + ["--tol", "1e-15"]) == 1
        err = capsys.readouterr().err
        assert "hint: --tol 1e-1" in err and "--transient" not in err
