"""Sweeps: resume after a kill, failed points, identical results on every executor."""

import signal
import subprocess
import sys
import time

import netCDF4
import numpy as np
import pytest
import xarray as xr

from blademodel.sweep import Study, load_study, open_result, run_study
from blademodel.zheng2022.studies import paper_figures

STUDY = Study(name="t", base={"model": "blade_pair", "friction": "bilinear"}, laws=["coulomb", "bilinear"],
              sweep={"gamma": {"start": 2, "stop": 10, "num": 4}},
              run={"transient": 30, "periods": 8, "steps_per_period": 300, "lyapunov_periods": 8,
                   "vibration_reduction": True})


def variant(**changes):
    """STUDY with ``changes``, validated (nested mappings replace the old ones)."""
    data = STUDY.model_dump(exclude={"source"})
    data.update(changes)
    return Study.model_validate(data)


def _data(path):
    ds = open_result(path)
    return ds.drop_attrs()


def test_serial_process_and_dask_results_are_identical(tmp_path):
    distributed = pytest.importorskip("distributed")
    run_study(STUDY, tmp_path / "serial.nc", workers=1, progress=None)
    run_study(STUDY, tmp_path / "proc.nc", workers=2, progress=None)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        run_study(STUDY, tmp_path / "dask.nc", scheduler=cluster.scheduler_address, progress=None)
    serial = _data(tmp_path / "serial.nc")
    assert int(serial["done"].sum()) == 8 and (serial["error"] == "").all()
    for other in ("proc.nc", "dask.nc"):
        xr.testing.assert_identical(serial, _data(tmp_path / other))   # bit for bit


def test_failed_point_is_recorded_and_the_rest_finish(tmp_path):
    bad = variant(laws=None, sweep={"gamma": {"values": [1.0, 1000.0, 3.0]}})
    run_study(bad, tmp_path / "bad.nc", workers=1, progress=None)
    ds = open_result(tmp_path / "bad.nc")
    errors = list(ds["error"].values)
    assert errors[0] == "" and errors[2] == ""
    assert "StepTooLargeError" in errors[1] and "steps_per_period >=" in errors[1]   # gamma = 1000 is too stiff
    assert int(ds["done"].sum()) == 3
    assert np.isfinite(ds["poincare_x1"].values[[0, 2]]).all() and np.isnan(ds["poincare_x1"].values[1]).all()


def test_killed_sweep_resumes_to_the_same_file(tmp_path):
    study_file = tmp_path / "study.yaml"
    # a point takes about 0.15 s (300 periods), so the kill, polled every 20 ms, lands mid-sweep
    # however fast the machine starts the run; 4 short points could all finish between two polls
    slow = variant(laws=None, sweep={"gamma": {"start": 2, "stop": 10, "num": 10}},
                   run={**STUDY.run.model_dump(), "transient": 300})
    study_file.write_text(slow.model_dump_json())
    full, killed = tmp_path / "full.nc", tmp_path / "killed.nc"
    cmd = [sys.executable, "-m", "blademodel", "sweep", str(study_file), "--workers", "1", "--no-plot"]
    run_study(slow, full, workers=1, progress=None)   # the reference, uninterrupted, in this process
    proc = subprocess.Popen(cmd + ["--out", str(killed)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 120
    done = 0
    while time.time() < deadline and proc.poll() is None:
        try:
            with netCDF4.Dataset(killed) as ds:
                done = int(np.sum(ds["done"][:]))
        except (OSError, RuntimeError):
            pass
        if done >= 1:
            break
        time.sleep(0.02)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    with netCDF4.Dataset(killed) as ds:
        assert 1 <= int(np.sum(ds["done"][:])) < 10, "the kill must land mid-sweep"
    subprocess.run(cmd + ["--out", str(killed)], check=True, capture_output=True)
    xr.testing.assert_identical(_data(full), _data(killed))


def test_resume_refuses_a_file_of_another_study(tmp_path):
    run_study(variant(laws=None, sweep={"gamma": {"values": [2.0]}}), tmp_path / "a.nc", workers=1, progress=None)
    other = variant(laws=None, sweep={"gamma": {"values": [3.0]}})
    with pytest.raises(ValueError, match="different study"):
        run_study(other, tmp_path / "a.nc", workers=1, progress=None)


def test_warm_start_chains_points(tmp_path):
    sweep = {"gamma": {"values": [4.0, 4.0]}}
    warm = variant(laws=None, sweep=sweep, run={**STUDY.run.model_dump(), "warm_start": True})
    run_study(warm, tmp_path / "w.nc", progress=None)
    ds = open_result(tmp_path / "w.nc")
    cold = open_result(run_study(variant(laws=None, sweep=sweep), tmp_path / "c.nc", workers=1, progress=None))
    # The first point starts from rest either way; the second continues the first
    # (warm), so it differs from its cold twin while the cold twins are equal.
    np.testing.assert_array_equal(ds["poincare_x1"][0], cold["poincare_x1"][0])
    np.testing.assert_array_equal(cold["poincare_x1"][0], cold["poincare_x1"][1])
    assert not np.array_equal(ds["poincare_x1"][1], cold["poincare_x1"][1])


def test_every_paper_figure_has_a_valid_study():
    figs = paper_figures()
    assert sorted(figs) == [f"fig{n:02d}" for n in range(5, 20)]
    for name, path in figs.items():
        study = load_study(path)
        assert study.name == name and (study.sweep or study.cases)
        if study.plot == "reduction":
            assert study.laws == ["coulomb", "bilinear"] and study.run.vibration_reduction
