"""What a sweep point observes, one rule for every model: the first mass's coordinates, or ``run.observe``."""

import json

import numpy as np
import pytest
import xarray as xr

from blademodel.sweep import Study, run_study
from blademodel.sweep.storage import study_signature

M, K, C, KC, GAP, FORCE, W = 1.0, 100.0, 4.0, 100.0, -0.01, 0.1, 9.0
BASE = {"model": "components", "name": "wall",
        "parameters": {"omega": W},
        "masses": [{"name": "m", "m": M, "dofs": ["x"]}],
        "springs": [{"a": "x_m", "k": K}], "dampers": [{"a": "x_m", "c": C}],
        "forces": [{"mass": "m", "amplitude": FORCE, "omega": "omega"}],
        "contacts": [{"name": "wall", "bodies": ["m", "ground"], "alpha": 1.5707963267948966, "gap": GAP,
                      "k": KC}]}
RUN = {"transient": 60, "periods": 20, "steps_per_period": 1000, "event_tol": 1e-10, "lyapunov_periods": 0,
       "vibration_reduction": True, "history_periods": 0, "observe": None}


def test_pd_and_sections_of_any_model_follow_one_rule():
    """A components model whose coordinate is ``x_m`` (no ``x1``): a preloaded frictionless wall that never opens
    adds its stiffness and a static offset. P_d and the Poincare samples come from the first mass's coordinate and
    equal the closed forms: mean square ``d^2 + X^2 / 2`` with and without the wall, samples on ``d + X sin(...)``."""
    from blademodel.config import config_from_data
    from blademodel.sweep.point import observed, run_point

    m, k, c, kc, gap, F, w = M, K, C, KC, GAP, FORCE, W
    base, run = BASE, RUN
    assert observed(config_from_data(dict(base)).build()) == ("x_m",)
    out = run_point(base, {}, run)
    assert "error" not in out, out.get("error")
    assert out["events"] == 0   # the wall never lets go
    d = -kc * (-gap) / (k + kc)   # delta = x - gap > 0: N = kc (x - gap) pushes x back
    X = F / np.hypot(k + kc - m * w ** 2, c * w)
    X0 = F / np.hypot(k - m * w ** 2, c * w)
    P, P0 = d ** 2 + X ** 2 / 2, X0 ** 2 / 2
    np.testing.assert_allclose([out["P"], out["P0"]], [P, P0], rtol=1e-6)
    np.testing.assert_allclose(out["Pd"], (P0 - P) / P0 * 100, rtol=1e-6)
    phase = np.arctan2(c * w, k + kc - m * w ** 2)
    t = 2 * np.pi / w * np.arange(61, 81)
    np.testing.assert_allclose(out["poincare_x1"], d + X * np.sin(w * t - phase), atol=1e-8 * X)


def test_observe_names_the_coordinates_and_the_file_says_which(tmp_path):
    study = {"name": "wall", "base": BASE, "sweep": {"omega": {"values": [W]}},
             "run": {k: v for k, v in {**RUN, "observe": ["x_m"]}.items() if k != "event_tol"}}
    path = run_study(Study.model_validate(study), tmp_path / "wall.nc", workers=1, progress=None, log=None)
    ds = xr.open_dataset(path)
    assert ds.attrs["observed"] == "x_m"
    assert ds["poincare_x1"].attrs["long_name"].startswith("x_m at the end")
    assert ds["P"].attrs["long_name"].startswith("mean square of x_m")
    default = run_study(Study.model_validate({**study, "run": {**study["run"], "observe": None}}),
                        tmp_path / "default.nc", workers=1, progress=None, log=None)
    np.testing.assert_array_equal(xr.open_dataset(default)["Pd"].values, ds["Pd"].values)


def test_a_name_that_is_no_coordinate_is_refused_before_any_work(tmp_path):
    study = {"name": "wall", "base": BASE, "sweep": {"omega": {"values": [W]}},
             "run": {"observe": ["x1"], "transient": 1, "periods": 2}}
    with pytest.raises(ValueError, match=r"run.observe = \['x1'\]: 'x1' is not a coordinate of the model \(x_m\)"):
        run_study(Study.model_validate(study), tmp_path / "bad.nc", workers=1, progress=None, log=None)
    assert not (tmp_path / "bad.nc").exists()


def test_files_written_before_claims_and_observe_still_resume():
    """Those fields are new; a study without them signs as before (the signature decides whether a file resumes)."""
    study = Study.model_validate({"name": "s", "base": {"model": "blade_pair"}, "sweep": {"gamma": {"values": [1.0]}},
                                  "claims": [{"at": {"gamma": 1.0}, "motion": "P1"}]})
    old = json.loads(study.model_dump_json())
    old.pop("claims")
    old["run"].pop("observe")
    assert study_signature(study.model_dump_json()) == study_signature(json.dumps(old))
    changed = study.model_copy(update={"run": study.run.model_copy(update={"observe": ["x1"]})})
    assert study_signature(changed.model_dump_json()) != study_signature(study.model_dump_json())
