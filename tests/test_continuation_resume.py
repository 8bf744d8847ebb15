"""Nothing a continuation computed is lost: checkpoints, Ctrl-C and SIGTERM keep the points, and a run resumes."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from blademodel.orbits import ContinuationInterrupted, continuation
from blademodel.orbits.branch_file import load_branch, save_branch
from blademodel.zheng2022 import BladePair

START, STOP, LOCATE_TOL = 280.0, 300.0, 1e-7
YAML = str(Path(__file__).resolve().parent.parent / "models" / "blade_pair_bilinear.yaml")


@pytest.fixture(scope="module")
def full():
    """The bilinear pair's branch over 280-300 rad/s, uninterrupted (rising, with grazing points)."""
    return continuation(BladePair(friction="bilinear"), "omega", START, STOP, workers=1)


def _interrupted_at(point, checkpoints):
    def progress(k, value):
        if k == point:
            raise KeyboardInterrupt

    with pytest.raises(ContinuationInterrupted) as e:
        continuation(BladePair(friction="bilinear"), "omega", START, STOP, workers=1, progress=progress,
                     checkpoint=checkpoints.append, checkpoint_every=0.0)
    return e.value


def test_an_interrupted_continuation_resumes_onto_the_same_branch(full, tmp_path):
    """Ctrl-C keeps the points found (the uninterrupted run's, bit for bit) and the checkpoints before it; the branch
    resumed from them, in memory or from its file, reaches the end through the same special points, each after the
    point it is indexed by, with no point twice."""
    assert full.complete and full.message.startswith("reached") and np.all(np.diff(full.params) > 0)
    assert len(full.special) >= 3
    checkpoints = []
    stop = _interrupted_at(25, checkpoints)
    assert isinstance(stop, KeyboardInterrupt)
    part = stop.branch
    assert not part.complete and part.message.startswith("interrupted at omega")
    assert np.array_equal(part.params, full.params[:25]) and np.array_equal(part.modes, full.modes[:25])
    assert [len(c.params) for c in checkpoints] == list(range(2, 25))   # after every new point, as asked
    assert all(not c.complete and np.array_equal(c.params, full.params[:len(c.params)]) for c in checkpoints)
    from blademodel.plots.branch import branch_figure
    assert "(unfinished: interrupted at omega" in branch_figure(part, "x1").axes[0].get_title()
    assert "unfinished" not in branch_figure(full, "x1").axes[0].get_title()

    resumed = continuation(BladePair(friction="bilinear"), "omega", START, STOP, workers=1, resume=part)
    assert resumed.complete and resumed.message == full.message
    assert np.array_equal(resumed.params[:24], full.params[:24]) and np.all(np.diff(resumed.params) > 0)
    assert abs(resumed.params[24] - full.params[24]) < 1e-12 * STOP   # shot again from its own orbit
    assert [q.kind for q in resumed.special] == [q.kind for q in full.special]
    span = STOP - START
    for q, r in zip(resumed.special, full.special):
        assert abs(q.param - r.param) <= 2 * LOCATE_TOL * span
        assert resumed.params[q.index] <= q.param <= resumed.params[q.index + 1]
    assert np.all(resumed.residuals <= 1e-10) and resumed.modes.shape == (len(resumed.params), 1)
    assert resumed.integrations > part.integrations

    shorter = continuation(BladePair(friction="bilinear"), "omega", START, STOP, workers=1, resume=part, max_points=30)
    assert len(shorter.params) == 30 and shorter.message.startswith("stopped after max_points = 30 points")

    path = tmp_path / "part.nc"
    save_branch(part, path)
    back = load_branch(path)
    assert not back.complete and np.array_equal(back.modes, part.modes)
    again = continuation(BladePair(friction="bilinear"), "omega", START, STOP, workers=1, resume=back)
    assert np.array_equal(again.params, resumed.params) and np.array_equal(again.states, resumed.states)


def test_a_ctrl_c_that_compiled_code_swallowed_stops_the_continuation_at_the_next_point(full):
    """With the command line's handlers (:func:`blademodel.interrupts.handled`), a signal whose exception was
    dropped (raised inside netCDF4's or llvmlite's compiled code) still stops the branch, one point later."""
    import threading

    from blademodel import interrupts
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signal handlers are set on the main thread only")

    def progress(k, value):
        if k == 6:
            try:
                os.kill(os.getpid(), signal.SIGTERM)
                time.sleep(5)
            except KeyboardInterrupt:
                swallowed.append(k)

    swallowed = []
    with interrupts.handled(), pytest.raises(ContinuationInterrupted) as e:
        continuation(BladePair(friction="bilinear"), "omega", START, STOP, workers=1, progress=progress)
    assert swallowed == [6] and np.array_equal(e.value.branch.params, full.params[:7])


def test_a_ring_resumes_in_the_contact_modes_it_was_saved_in(tmp_path):
    """On the per-contact kernel a mode is an array, one entry per contact: saved per point, it starts the resumed
    run's first orbit, which is the interrupted run's last one again."""
    from blademodel.config import BladedDisk
    cfg = BladedDisk(blades=4, engine_order=1, friction="coulomb", mistuning=[0, 0.03, -0.02, 0.01])

    def progress(k, value):
        if k == 3:
            raise KeyboardInterrupt

    with pytest.raises(ContinuationInterrupted) as e:
        continuation(cfg, "omega", 285.0, 295.0, max_points=5, workers=1, progress=progress)
    path = tmp_path / "ring.nc"
    save_branch(e.value.branch, path, cfg)
    part = load_branch(path)
    assert part.modes.shape == (3, 4) and not part.complete
    resumed = continuation(cfg, "omega", 285.0, 295.0, max_points=5, workers=1, resume=part)
    assert len(resumed.params) == 5 and resumed.complete and np.array_equal(resumed.modes[:3], part.modes)
    assert np.array_equal(resumed.params[:2], part.params[:2])
    assert abs(resumed.params[2] - part.params[2]) < 1e-12 * 295.0 and np.all(resumed.residuals <= 1e-10)


def test_a_branch_of_another_field_or_range_is_not_resumed(full):
    with pytest.raises(ValueError, match="continued in 'omega' with period 1, not in 'gamma'"):
        continuation(BladePair(friction="bilinear"), "gamma", 7.0, 7.5, resume=full)
    with pytest.raises(ValueError, match="lies outside"):
        continuation(BladePair(friction="bilinear"), "omega", 310.0, 320.0, resume=full)


def _command(out, *extra):
    # one thread: the run does not slow the test's polling down
    return ["continue", YAML, "--param", "omega", "--from", str(START), "--to", str(STOP), "--out", str(out),
            "--workers", "1", *extra]


def test_a_killed_continue_command_keeps_its_points_and_resumes(tmp_path, capsys):
    """``blademodel continue --out`` saves the branch as it goes; SIGTERM saves the points found and exits 130
    saying how to resume; the same command resumes from the file (the points before the last one kept), then,
    finished, reads it back; other options compute a new branch."""
    from blademodel.cli import main
    out = tmp_path / "b.nc"
    env = {**os.environ, "BLADEMODEL_CHECKPOINT_SECONDS": "0"}
    proc = subprocess.Popen([sys.executable, "-m", "blademodel", *_command(out)], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and proc.poll() is None:
        if out.exists() and len(load_branch(out).params) >= 5:
            break
        time.sleep(0.02)
    assert proc.poll() is None, "the run ended before it could be killed"
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "are saved in" in err and "run the same command again to resume" in err
    killed = load_branch(out)
    assert not killed.complete and len(killed.params) >= 5 and killed.message.startswith("interrupted")

    assert main(_command(out)) == 0
    err = capsys.readouterr().err
    assert f"resuming the branch saved in {out}: {len(killed.params)} points" in err
    done = load_branch(out)
    k = len(killed.params) - 1
    assert done.complete and done.message.startswith("reached") and np.all(np.diff(done.params) > 0)
    assert np.array_equal(done.params[:k], killed.params[:k]) and np.array_equal(done.states[:k], killed.states[:k])

    before = out.read_bytes()
    assert main(_command(out)) == 0
    assert "finished" in capsys.readouterr().err and out.read_bytes() == before
    assert main(_command(out, "--max-points", "5")) == 0
    assert "resuming" not in capsys.readouterr().err
    assert len(load_branch(out).params) == 5


def test_a_branch_point_with_its_mode_row_starts_a_branch_of_its_own():
    """A branch point's section state and its row of ``Branch.modes`` (one entry on the product-mode kernel) start
    a continuation where it stands: its first orbit is that point's (it failed: an array was no mode number)."""
    b = continuation(BladePair(friction="coulomb"), "omega", 300.0, 301.0, workers=1)
    i = len(b.params) // 2
    again = continuation(BladePair(friction="coulomb"), "omega", float(b.params[i]), 301.0, guess=b.states[i],
                         mode=b.modes[i], transient=0, workers=1)
    np.testing.assert_allclose(again.states[0], b.states[i], rtol=0, atol=1e-9 * np.abs(b.states).max())
    with pytest.raises(ValueError, match=r"mode = array\(\[0, 1\]\)"):
        continuation(BladePair(friction="coulomb"), "omega", 300.0, 301.0, guess=b.states[i], mode=np.array([0, 1]),
                     transient=0, workers=1)
