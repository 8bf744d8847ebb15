"""A study's claims beside its measurements: the rows, the tally, reproduce's table and summary."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from pydantic import ValidationError

from blademodel.cli import main
from blademodel.sweep import Study, open_result
from blademodel.sweep.claims import check_claims, claims_table, tally
from blademodel.sweep.point import motion_code, motion_label

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "tools"))


def _result(gammas, labels, errors=None, done=None, lyap=None, pd=None, law="coulomb"):
    """A result as :func:`open_result` gives it, with the variables the claims read."""
    n = len(gammas)
    data = {"param_gamma": ("point", np.asarray(gammas, float)), "law": ("point", np.array([law] * n)),
            "motion": ("point", np.array([motion_code(x) for x in labels])),
            "error": ("point", np.array(errors or [""] * n)),
            "done": ("point", np.array(done or [True] * n)),
            "lyapunov": ("point", np.asarray(lyap or [np.nan] * n, float))}
    if pd is not None:
        data["Pd"] = ("point", np.asarray(pd, float))
    return xr.Dataset(data)


STUDY = {"name": "s", "base": {"model": "blade_pair", "friction": "coulomb"},
         "sweep": {"gamma": {"start": 1, "stop": 9, "num": 5}},
         "claims": [{"at": {"gamma": 5.3}, "motion": "P2"}, {"at": {"gamma": 8.8}, "motion": "chaos"},
                    {"at": {"gamma": 1}, "motion": "P1"}]}


def test_rows_measure_the_nearest_grid_point_and_judge_agreement():
    ds = _result([1, 3, 5, 7, 9], ["P1", "P1", "P2", "P4", "chaos"], lyap=[-0.3, -0.2, -0.1, -0.05, 0.4],
                 pd=[10, 20, 30, 40, 50])
    rows = check_claims(Study.model_validate(STUDY), ds)
    assert [r["point"]["gamma"] for r in rows] == [5.0, 9.0, 1.0]
    assert [(r["paper"], r["measured"], r["agrees"]) for r in rows] == [("P2", "P2", True), ("chaos", "chaos", True),
                                                                        ("P1", "P1", True)]
    assert [r["lyapunov"] for r in rows] == [-0.1, 0.4, -0.3] and [r["P_d"] for r in rows] == [30, 50, 10]
    ds = _result([1, 3, 5, 7, 9], ["P1", "P1", "P1", "P4", "P8"])
    rows = check_claims(Study.model_validate(STUDY), ds)
    assert [r["agrees"] for r in rows] == [False, False, True] and tally(rows) == (1, 3)
    assert rows[0]["P_d"] is None and rows[0]["lyapunov"] is None


def test_failed_and_missing_points_are_not_counted():
    ds = _result([1, 3, 5, 7, 9], ["P1", "P1", "P1", "P1", "P1"],
                 errors=["", "", "StepTooLargeError: h > limit\nmore", "", ""], done=[True, True, True, True, False])
    rows = check_claims(Study.model_validate(STUDY), ds)
    assert rows[0]["measured"] == "failed: StepTooLargeError: h > limit" and rows[0]["agrees"] is None
    assert rows[1]["measured"] == "not run" and rows[1]["agrees"] is None
    assert tally(rows) == (1, 1)
    lines = claims_table(rows)
    assert "nearest to 5.3" in lines[1]
    assert lines[-1] == "1 of 1 measured claims agree with the paper (2 not measured)"


@pytest.mark.parametrize("claim, message", [
    ({"at": {"gamma": 4}, "motion": "period-3"}, "motion 'period-3': expected P1 ... P16"),
    ({"at": {"gap": 4e-5}, "motion": "P3"}, "claims[0].at names ['gap']"),
    ({"at": {"gamma": 4}, "motion": "P3", "law": "bilinear"}, "claims[0].law = 'bilinear' is not a law"),
])
def test_bad_claims_name_the_field_and_value(claim, message):
    with pytest.raises(ValidationError, match=message.replace("[", r"\[").replace("]", r"\]").replace(".", r"\.")):
        Study.model_validate({**STUDY, "claims": [claim]})


CASES = {"name": "fig01", "title": "two cases", "paper": "text",
         "base": {"model": "blade_pair", "friction": "bilinear"},
         "cases": [{"gamma": 3.0}, {"gamma": 9.0}],
         "claims": [{"at": {"gamma": 3.0}, "motion": "P1"}, {"at": {"gamma": 9.0}, "motion": "P3"}],
         "plot": "cases", "run": {"transient": 10, "periods": 8, "steps_per_period": 200, "vibration_reduction": True},
         "quick": {"transient": 10, "periods": 8}}


def test_reproduce_prints_and_writes_the_claims_and_the_report_table_uses_the_same_rows(tmp_path, monkeypatch,
                                                                                         capsys):
    import yaml
    from reproduction_tables import claims_markdown

    studies = tmp_path / "studies"
    studies.mkdir()
    (studies / "fig01.yaml").write_text(yaml.safe_dump(CASES))
    monkeypatch.setenv("BLADEMODEL_STUDIES", str(studies))
    assert main(["reproduce", "fig01", "--out", str(tmp_path / "out"), "--workers", "1", "--no-plot"]) == 0
    printed = capsys.readouterr().out
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    rows = summary["fig01"]["claims"]
    ds = open_result(tmp_path / "out" / "fig01" / "fig01.nc")
    assert [r["measured"] for r in rows] == [motion_label(int(m)) for m in ds["motion"].values]
    assert [r["agrees"] for r in rows] == [r["measured"] == r["paper"] for r in rows]
    assert all(r["P_d"] is not None for r in rows)   # the study computes P_d
    agree = sum(r["agrees"] for r in rows)
    assert summary["claims_tally"] == {"agree": agree, "measured": 2, "claims": 2}
    assert f"{agree} of 2 measured claims agree with the paper" in printed
    for r in rows:
        assert f"gamma = {r['point']['gamma']:g}" in printed
    table = claims_markdown([str(tmp_path / "out")])
    cells = [[c.strip() for c in line.strip("|").split("|")][4] for line in table.splitlines()[2:4]]
    assert [c.strip("*").split(" (")[0] for c in cells] == [r["measured"] for r in rows]
    assert [c.startswith("**") for c in cells] == [r["agrees"] for r in rows]
    assert table.splitlines()[-1].endswith(f"**{agree} of 2** |")
