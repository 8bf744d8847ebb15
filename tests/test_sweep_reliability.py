"""Issue #13, sweeps and result files: no lost or mixed results, no hangs, no orphans, no tracebacks.

One test per fault a user met; each checks the exit code, the message, the files
on disk and that no process is left behind.
"""

import os
import signal
import socket
import subprocess
import sys
import time

import numpy as np
import pytest

from blademodel.sweep import Study, open_result, run_study
from blademodel.sweep.errors import ResultFileError
from blademodel.sweep.lock import lock_path

from sweep_tools import (SLOW, TINY, cli, cli_env, done_count, kill_all, one_line, raw_contents, start, tagged,
                         wait_until, write_study)

linux_only = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="processes found through /proc")


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The tiny study run once, uninterrupted."""
    path = tmp_path_factory.mktemp("ref") / "tiny.nc"
    run_study(Study.model_validate(TINY), path, workers=1, progress=None, log=None)
    return path


def _copy(src, dst):
    dst.write_bytes(src.read_bytes())
    return dst


# ----------------------------------------------------------------- truncated or damaged result files

@pytest.mark.parametrize("cut", ["tail", "half"])
def test_truncated_result_is_detected_and_recomputed(tmp_path, reference, cut):
    size = reference.stat().st_size
    damaged = _copy(reference, tmp_path / "tiny.nc")
    # past the header either way: the data start with the point coordinate, 0 1 2 3 as big-endian int32
    data = reference.read_bytes().find(np.arange(4, dtype=">i4").tobytes())
    assert 0 < data < size - 8
    os.truncate(damaged, size - 8 if cut == "tail" else (data + size) // 2)
    with pytest.raises(ResultFileError, match="damaged: the file is cut short"):
        open_result(damaged)              # never zeros passed off as data
    said = []
    run_study(Study.model_validate(TINY), damaged, workers=1, progress=None, log=said.append)
    assert any("is damaged: the file is cut short" in s and "running the others again" in s for s in said), said
    assert damaged.read_bytes() == reference.read_bytes()   # recomputed: bit for bit the uninterrupted file


def test_flipped_bytes_in_a_done_point_are_recomputed(tmp_path, reference):
    damaged = _copy(reference, tmp_path / "tiny.nc")
    ds = open_result(reference)
    value = ds["poincare_x1"].values[2, 1].tobytes()
    blob = bytearray(damaged.read_bytes())
    at = blob.find(value[::-1] if sys.byteorder == "little" else value)   # classic NetCDF is big-endian
    assert at > 0
    blob[at] ^= 0x40
    damaged.write_bytes(bytes(blob))
    with pytest.raises(ResultFileError, match=r"1 done point\(s\) fail their checksum \(2\)"):
        open_result(damaged)
    said = []
    run_study(Study.model_validate(TINY), damaged, workers=1, progress=None, log=said.append)
    assert any("keeping the 3 point(s) that verify" in s for s in said), said
    assert damaged.read_bytes() == reference.read_bytes()


def test_plot_of_a_damaged_file_is_refused(tmp_path, reference):
    damaged = _copy(reference, tmp_path / "tiny.nc")
    os.truncate(damaged, reference.stat().st_size - 8)
    r = cli("plot", damaged, "--out", tmp_path / "figs")
    assert r.returncode == 2
    assert "damaged" in one_line(r.stderr) and str(damaged) in r.stderr
    assert not (tmp_path / "figs").exists()


# ----------------------------------------------------------------- two sweeps on one file

@linux_only
def test_second_sweep_on_the_same_file_is_refused(tmp_path, reference):
    study = write_study(tmp_path, TINY)
    out = tmp_path / "tiny.nc"
    holder = subprocess.Popen([sys.executable, "-c",
                               "import sys, time; from blademodel.sweep.lock import ResultLock; "
                               "ResultLock(sys.argv[1]).acquire(); print('locked', flush=True); time.sleep(120)",
                               str(out)], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        r = cli("sweep", study, "--out", out, "--workers", "1", "--no-plot")
        assert r.returncode == 1
        message = one_line(r.stderr)
        assert message.startswith(f"error: {out} is being written by another sweep")
        assert f"process {holder.pid} on " in message
        assert not out.exists()                         # the second sweep wrote nothing
    finally:
        holder.kill()
        holder.wait()
    # The lock dies with its owner, even killed: the next sweep runs.
    r = cli("sweep", study, "--out", out, "--workers", "1", "--no-plot")
    assert r.returncode == 0, r.stderr
    assert raw_contents(out) == raw_contents(reference)
    assert not lock_path(out).exists()


@linux_only
def test_two_sweeps_started_together_do_not_mix(tmp_path):
    # long enough points (~2 s each) that the first sweep still runs when the second has started; held still (SIGSTOP)
    # while the second one runs, so that on a loaded machine it cannot finish first (in CI beside other work the
    # second sweep's start-up outlasted the first sweep, and it found a finished file of another study)
    longer = {**SLOW["run"], "transient": 8000}
    study = write_study(tmp_path, {**SLOW, "run": longer, "sweep": {"gamma": {"values": [3.0, 4.0]}}})
    out, tag = tmp_path / "slow.nc", "two-sweeps-" + str(os.getpid())
    first = start("sweep", study, "--out", out, "--workers", "1", "--no-plot", tag=tag)
    try:
        assert wait_until(lambda: lock_path(out).exists() and lock_path(out).read_text(), 30)
        other = write_study(tmp_path, {**SLOW, "run": longer, "sweep": {"gamma": {"values": [5.0]}}}, "other.yaml")
        os.kill(first.pid, signal.SIGSTOP)
        try:
            r = cli("sweep", other, "--out", out, "--workers", "1", "--no-plot")
        finally:
            os.kill(first.pid, signal.SIGCONT)
        assert r.returncode == 1 and f"process {first.pid} on" in one_line(r.stderr)
        assert first.wait(60) == 0
    finally:
        kill_all(tag)
    ds = open_result(out)
    assert list(ds["param_gamma"].values) == [3.0, 4.0] and int(ds["done"].sum()) == 2


# ----------------------------------------------------------------- orphans

@linux_only
def test_workers_exit_when_the_parent_is_killed(tmp_path):
    study = write_study(tmp_path, SLOW)
    out, tag = tmp_path / "slow.nc", "orphans-" + str(os.getpid())
    parent = start("sweep", study, "--out", out, "--workers", "2", "--no-plot", tag=tag)
    try:
        assert wait_until(lambda: len(tagged(tag)) >= 3, 60), "the pool must have started"
        time.sleep(0.3)                                   # workers busy in the compiled kernel
        parent.kill()
        parent.wait()
        assert wait_until(lambda: not tagged(tag), 5), f"workers left running: {tagged(tag)}"
    finally:
        kill_all(tag)
    assert done_count(out) < 6


WATCHED_CHILD = """
import multiprocessing, os, sys, time
from blademodel.sweep import workers

def child(parent):
    workers._set_parent_death_signal = lambda sig: False   # as where prctl does not exist
    workers.init_worker(parent)
    time.sleep(120)

if __name__ == "__main__":
    p = multiprocessing.get_context("fork").Process(target=child, args=(os.getpid(),))
    p.start()
    print(p.pid, flush=True)
    time.sleep(120)
"""


@linux_only
def test_the_watchdog_alone_ends_a_worker_whose_parent_died(tmp_path):
    script = tmp_path / "watched.py"
    script.write_text(WATCHED_CHILD)
    tag = "watchdog-" + str(os.getpid())
    parent = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True, env=cli_env(tag))
    try:
        child = int(parent.stdout.readline())
        assert child in tagged(tag)
        parent.kill()
        parent.wait()
        assert wait_until(lambda: child not in tagged(tag), 3), "the watchdog did not end the worker"
    finally:
        kill_all(tag)


# ----------------------------------------------------------------- empty file

def test_empty_result_file_is_refused_with_a_way_forward(tmp_path, reference):
    study = write_study(tmp_path, TINY)
    out = tmp_path / "tiny.nc"
    out.write_bytes(b"")
    r = cli("sweep", study, "--out", out, "--workers", "1", "--no-plot")
    assert r.returncode == 2
    assert one_line(r.stderr) == (f"error: {out} is empty (0 bytes), not a result file; run the sweep with "
                                  f"--restart to discard it and start again")
    assert out.stat().st_size == 0 and not lock_path(out).exists()
    r = cli("plot", out)
    assert r.returncode == 2 and one_line(r.stderr).startswith(f"error: {out} is empty (0 bytes)")
    r = cli("sweep", study, "--out", out, "--workers", "1", "--no-plot", "--restart")
    assert r.returncode == 0, r.stderr
    assert raw_contents(out) == raw_contents(reference)


def test_unreadable_result_file_is_refused(tmp_path):
    study = write_study(tmp_path, TINY)
    out = tmp_path / "tiny.nc"
    out.write_bytes(b"not a netcdf file at all\n" * 10)
    r = cli("sweep", study, "--out", out, "--workers", "1", "--no-plot")
    assert r.returncode == 2
    message = one_line(r.stderr)
    assert f"{out} is not a readable result file" in message and "--restart" in message


# ----------------------------------------------------------------- failing points

def test_a_sweep_whose_every_point_fails_says_so_and_fails(tmp_path):
    # gamma = 1000 needs more steps than 200 per period: every point is refused.
    study = write_study(tmp_path, {**TINY, "sweep": {"gamma": {"values": [1000.0, 2000.0]}}})
    out = tmp_path / "bad.nc"
    r = cli("sweep", study, "--out", out, "--workers", "1")
    assert r.returncode == 1
    assert "Traceback" not in r.stderr
    assert f"{out}: 2 of 2 points failed:" in r.stderr
    assert "  2 x StepTooLargeError (points 0, 1), e.g. StepTooLargeError: steps_per_period = 200" in r.stderr
    assert f"error: every point of {out} failed" in r.stderr
    assert not list(tmp_path.glob("*.png"))


def test_a_partly_failed_sweep_sums_up_its_failures(tmp_path):
    study = write_study(tmp_path, {**TINY, "sweep": {"gamma": {"values": [3.0, 1000.0]}}})
    out = tmp_path / "part.nc"
    r = cli("sweep", study, "--out", out, "--workers", "1", "--no-plot")
    assert r.returncode == 0
    assert f"{out}: 1 of 2 points failed:" in r.stderr and "(points 1)" in r.stderr


# ----------------------------------------------------------------- names

def test_a_study_name_cannot_escape_the_output_folder(tmp_path):
    work = tmp_path / "work"
    work.mkdir()
    study = write_study(work, {**TINY, "name": "../escaped"})
    r = cli("sweep", study, "--workers", "1", cwd=work)
    assert r.returncode == 2
    message = one_line(r.stderr)
    assert message.startswith(f"error: {study}:1: name = '../escaped': a study name is a plain file name")
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["study.yaml", "work"]   # nothing written
    for bad in ("a/b", "..", ".hidden", "a\\b", ""):
        with pytest.raises(ValueError, match="plain file name"):
            Study.model_validate({**TINY, "name": bad})


# ----------------------------------------------------------------- Ctrl-C

@linux_only
def test_ctrl_c_during_a_sweep_says_how_to_resume(tmp_path, reference):
    # ``reference`` compiled the kernel, so the workers start at once and the Ctrl-C lands
    # mid-sweep (on a cold cache a compile can outlast the sweep's window); points of a
    # second or two leave the sweep well unfinished when the first is saved.
    study = write_study(tmp_path, {**SLOW, "run": {**SLOW["run"], "transient": 5000}})
    out, tag = tmp_path / "slow.nc", "ctrl-c-" + str(os.getpid())
    proc = start("sweep", study, "--out", out, "--workers", "2", "--no-plot", tag=tag)
    try:
        assert wait_until(lambda: done_count(out) >= 1, 60)
        os.killpg(proc.pid, signal.SIGINT)               # a terminal's Ctrl-C reaches the whole group
        _, err = proc.communicate(timeout=20)
        assert proc.returncode == 130
        saved = done_count(out)
        assert one_line(err) == (f"interrupted: {saved} of 6 points are saved in {out}; run the same command "
                                 f"again to resume")
        assert 1 <= saved < 6
        assert wait_until(lambda: not tagged(tag), 5), f"left running: {tagged(tag)}"
        assert not lock_path(out).exists()
    finally:
        kill_all(tag)


def test_a_ctrl_c_just_after_a_point_is_written_counts_it(tmp_path, monkeypatch):
    """The message counts what the file holds: a Ctrl-C between writing a point and counting it."""
    from blademodel.sweep import runner
    from blademodel.sweep.errors import SweepInterrupted
    real, calls = runner.storage.write_point, []

    def write_then_interrupt(path, index, out):
        real(path, index, out)
        calls.append(index)
        if len(calls) == 2:
            raise KeyboardInterrupt

    monkeypatch.setattr(runner.storage, "write_point", write_then_interrupt)
    out = tmp_path / "tiny.nc"
    with pytest.raises(SweepInterrupted, match=r"interrupted: 2 of 4 points are saved"):
        run_study(Study.model_validate(TINY), out, workers=1, progress=None, log=None)
    assert done_count(out) == 2


@linux_only
def test_ctrl_c_during_a_run_is_one_line(tmp_path):
    tag = "ctrl-c-run-" + str(os.getpid())
    model = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "models",
                         "blade_pair_bilinear.yaml")
    # Compiled first: Python sees a signal only between bytecodes, and one LLVM call of a cold
    # compile can take tens of seconds on a loaded machine; this test is about the run.
    assert cli("simulate", model, "--transient", "1", "--periods", "1", cwd=tmp_path).returncode == 0
    proc = start("simulate", model, "--transient", "200000", "--periods", "10", cwd=tmp_path, tag=tag)
    try:
        time.sleep(3)
        assert proc.poll() is None
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=20)
        assert proc.returncode == 130
        assert one_line(err) == "interrupted" and out == ""
    finally:
        kill_all(tag)


# ----------------------------------------------------------------- re-running a finished study

def test_rerunning_a_finished_study_says_it_reuses_the_result(tmp_path, reference):
    study = write_study(tmp_path, TINY)
    out = _copy(reference, tmp_path / "tiny.nc")
    before = out.stat().st_mtime_ns
    r = cli("sweep", study, "--out", out, "--workers", "1", "--no-plot")
    assert r.returncode == 0
    assert one_line(r.stderr) == (f"{out}: all 4 points are already done; using them "
                                  f"(--restart recomputes them)")
    assert out.stat().st_mtime_ns == before
    r = cli("sweep", study, "--out", out, "--workers", "1", "--no-plot", "--restart")
    assert r.returncode == 0 and r.stderr == ""
    assert out.stat().st_mtime_ns != before and out.read_bytes() == reference.read_bytes()


def test_resuming_says_how_much_is_done(tmp_path, reference):
    out = _copy(reference, tmp_path / "tiny.nc")
    import netCDF4
    with netCDF4.Dataset(out, "a") as ds:
        ds["done"][2:] = 0
    said = []
    run_study(Study.model_validate(TINY), out, workers=1, progress=None, log=said.append)
    assert said == [f"{out}: resuming: 2 of 4 points already done, running the other 2 (--restart starts over)"]
    assert out.read_bytes() == reference.read_bytes()


# ----------------------------------------------------------------- Dask scheduler

def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_unreachable_scheduler_is_named(tmp_path):
    pytest.importorskip("distributed")
    study = write_study(tmp_path, TINY)
    address = f"tcp://127.0.0.1:{_free_port()}"
    r = cli("sweep", study, "--out", tmp_path / "d.nc", "--scheduler", address, "--no-plot",
            env=cli_env(DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT="2s"))
    assert r.returncode == 1
    message = one_line(r.stderr)
    assert message.startswith(f"error: cannot reach the Dask scheduler at {address} (")
    assert message.endswith("check the address and that the scheduler is running")


def _without_checksums(src, dst):
    """A copy of ``src`` as blademodel wrote it before checksums (no ``checksum``, no ``tail``)."""
    import netCDF4
    with netCDF4.Dataset(src) as a, netCDF4.Dataset(dst, "w", format=a.data_model) as b:
        a.set_auto_maskandscale(False)
        a.set_auto_chartostring(False)
        for name, dim in a.dimensions.items():
            if name != "checksum_chars":
                b.createDimension(name, len(dim))
        b.setncatts({k: a.getncattr(k) for k in a.ncattrs()})
        for name, var in a.variables.items():
            if name in ("checksum", "tail"):
                continue
            fill = var.getncattr("_FillValue") if "_FillValue" in var.ncattrs() else None
            out = b.createVariable(name, var.dtype, var.dimensions, fill_value=fill)
            out.set_auto_maskandscale(False)
            out.set_auto_chartostring(False)
            out[:] = var[:]
    return dst


def test_a_file_from_before_checksums_still_resumes(tmp_path, reference):
    old = _without_checksums(reference, tmp_path / "old.nc")
    import netCDF4
    with netCDF4.Dataset(old, "a") as ds:
        ds["done"][2:] = 0
    said = []
    run_study(Study.model_validate(TINY), old, workers=1, progress=None, log=said.append)
    assert said[0] == (f"{old}: written by an older blademodel without checksums, so its points cannot be "
                       f"verified; --restart recomputes them")
    data, _ = raw_contents(old)
    ref, _ = raw_contents(reference)
    assert data == {k: v for k, v in ref.items() if k not in ("checksum", "tail")}
    assert int(open_result(old)["done"].sum()) == 4


def test_a_damaged_file_from_before_checksums_is_rebuilt_with_them(tmp_path, reference):
    old = _without_checksums(reference, tmp_path / "old.nc")
    import netCDF4
    with netCDF4.Dataset(old, "a") as ds:
        ds["done"][2:] = 0
        ds["param_gamma"][3] = 99.0          # the parameter table no longer the study's
    said = []
    run_study(Study.model_validate(TINY), old, workers=1, progress=None, log=said.append)
    assert any("its parameter or law table is damaged; keeping the 2 point(s)" in s for s in said), said
    assert old.read_bytes() == reference.read_bytes()   # rebuilt in the current layout, points sealed
