"""Figures of sweep results (:mod:`blademodel.plots`) and the ``blademodel plot`` command.

Most tests build result datasets in memory (the layout of
:mod:`blademodel.sweep.storage`) and read the plotted data back from the
figures' artists; the CLI tests write real result files with the storage
functions, without integrating anything.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from matplotlib.colors import to_rgba

from blademodel import cli
from blademodel.plots import (bifurcation_figure, case_figure, cases_figure, load_result, periodicity_map_figure,
                              plot_result, reduction_figure)
from blademodel.plots.common import FAILED, NOT_RUN, field_axis, motion_codes
from blademodel.plots.periodicity_map import CODE_COLORS
from blademodel.sweep import Study, points, storage

OMEGA = 290.0
GAP = 4e-5


def make_ds(fields, values, laws, motion, *, poincare=None, vpoincare=None, length_scale=GAP, pd=None,
            errors=None, done=None, history=None, study=None, lyapunov=None, samples=6):
    """An in-memory result dataset, as :func:`blademodel.sweep.open_result` returns it."""
    n = len(values)
    values = np.asarray(values, dtype=float).reshape(n, len(fields))
    rng = np.random.default_rng(0)
    poincare = rng.normal(size=(n, samples)) * GAP if poincare is None else np.asarray(poincare, float)
    vpoincare = rng.normal(size=(n, samples)) * GAP * OMEGA if vpoincare is None else np.asarray(vpoincare, float)
    data = {f"param_{f}": ("point", values[:, j]) for j, f in enumerate(fields)}
    data.update(
        law=("point", np.asarray(laws, dtype=str)),
        done=("point", np.ones(n, np.int8) if done is None else np.asarray(done, np.int8)),
        length_scale=("point", np.broadcast_to(np.asarray(length_scale, float), (n,)).copy()),
        motion=("point", np.asarray(motion, dtype=float)),
        lyapunov=("point", np.full(n, np.nan) if lyapunov is None else np.asarray(lyapunov, float)),
        Pd=("point", np.full(n, np.nan) if pd is None else np.asarray(pd, float)),
        poincare_x1=(("point", "sample"), poincare),
        poincare_vx1=(("point", "sample"), vpoincare),
        error=("point", np.asarray(errors if errors is not None else [""] * n, dtype=str)),
    )
    if history is not None:
        t, x, v = history
        data.update(history_t=(("point", "time"), t), history_x1=(("point", "time"), x),
                    history_vx1=(("point", "time"), v))
    st = {"name": "test", "title": "", "base": {"model": "blade_pair", "omega": OMEGA}, "sweep": {}, "cases": [],
          "run": {"steps_per_period": 50, "history_periods": 0}, "plot": "bifurcation"}
    st.update(study or {})
    return xr.Dataset(data, attrs={"study": st, "fields": list(fields)})


def scatter(ax, gid):
    found = [c for c in ax.collections if c.get_gid() == gid]
    assert len(found) == 1, f"one collection {gid!r} expected, got {len(found)}"
    return found[0].get_offsets()


# --------------------------------------------------------------------------- bifurcation


def test_bifurcation_points_are_poincare_samples_over_gap():
    gam = [1.0, 2.0, 3.0]
    ds = make_ds(["gamma"], gam * 2, ["coulomb"] * 3 + ["bilinear"] * 3, [1, 2, -2, 1, -1, 0],
                 length_scale=[GAP, GAP, GAP, 2 * GAP, 2 * GAP, 2 * GAP])
    fig = bifurcation_figure(ds)
    assert len(fig.axes) == 2
    for k, ax in enumerate(fig.axes):
        off = scatter(ax, "poincare")
        sel = slice(3 * k, 3 * k + 3)
        want_x = np.repeat(gam, 6)
        want_y = (ds.poincare_x1.values[sel] / ds.length_scale.values[sel, None]).ravel()
        np.testing.assert_allclose(off[:, 0], want_x)
        np.testing.assert_allclose(off[:, 1], want_y)
    assert "Coulomb" in fig.axes[0].get_title(loc="left") and "bilinear" in fig.axes[1].get_title(loc="left")
    assert "X_1" in fig.axes[0].get_ylabel()
    # chaos shaded around gamma = 3 in the Coulomb panel (one span), quasi + nonperiodic in the bilinear one
    assert len(fig.axes[0].patches) == 1 and len(fig.axes[1].patches) == 2
    x0, x1 = fig.axes[0].patches[0].get_x(), fig.axes[0].patches[0].get_x() + fig.axes[0].patches[0].get_width()
    assert x0 == pytest.approx(2.5) and x1 == pytest.approx(3.5)


def test_bifurcation_physical_units_for_preload_and_failed_points():
    ds = make_ds(["gap"], [-1e-5, 0.0, 2e-5], ["coulomb"] * 3, [1, np.nan, 1], length_scale=[-1e-5, np.nan, 2e-5],
                 errors=["", "RuntimeError: integration failed", ""],
                 poincare=[[1e-6] * 6, [np.nan] * 6, [3e-6] * 6])
    fig = bifurcation_figure(ds)
    ax = fig.axes[0]
    off = scatter(ax, "poincare")
    label, factor = field_axis("gap")
    assert factor == 1e6 and "\u00b5m" in label and ax.get_xlabel() == label
    np.testing.assert_allclose(off[:, 0], np.repeat([-10.0, 20.0], 6))
    np.testing.assert_allclose(off[:, 1], np.repeat([1.0, 3.0], 6))   # x1 in micrometres
    assert "\u00b5m" in ax.get_ylabel()
    np.testing.assert_allclose(scatter(ax, "failed")[:, 0], [0.0])
    assert motion_codes(ds).tolist() == [1, FAILED, 1]


def test_bifurcation_unknown_field():
    ds = make_ds(["gamma"], [1.0, 2.0], ["coulomb"] * 2, [1, 1])
    with pytest.raises(ValueError, match="not a field"):
        bifurcation_figure(ds, "F0")


# --------------------------------------------------------------------------- reduction


def test_reduction_one_line_per_law_with_stored_values():
    gam = [3.0, 1.0, 2.0]   # unsorted on purpose: the curve is drawn in field order
    pd = [30.0, 10.0, np.nan, 5.0, -4.0, 12.0]
    ds = make_ds(["gamma"], gam * 2, ["coulomb"] * 3 + ["bilinear"] * 3, [1] * 6, pd=pd)
    fig = reduction_figure(ds)
    ax = fig.axes[0]
    lines = {ln.get_gid(): ln for ln in ax.get_lines()}
    assert set(lines) == {"Pd:coulomb", "Pd:bilinear", "zero"}
    np.testing.assert_allclose(lines["Pd:coulomb"].get_xdata(), [1, 2, 3])
    np.testing.assert_allclose(lines["Pd:coulomb"].get_ydata(), [10, np.nan, 30])
    np.testing.assert_allclose(lines["Pd:bilinear"].get_ydata(), [-4, 12, 5])
    np.testing.assert_allclose(lines["zero"].get_ydata(), [0, 0])
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["Coulomb", "bilinear"]
    assert "%" in ax.get_ylabel()


def test_reduction_without_pd_is_an_error():
    ds = make_ds(["gamma"], [1.0, 2.0], ["coulomb"] * 2, [1, 1])
    with pytest.raises(ValueError, match="vibration_reduction"):
        reduction_figure(ds)


# --------------------------------------------------------------------------- periodicity map


def test_periodicity_map_codes_at_their_cells():
    g = [6.0, 7.0, 8.0]
    f0 = [40.0, 50.0]
    vals = [[a, b] for a in g for b in f0]   # first field slow, as points() orders them
    codes = [1, 2, -2, 3, -1, 16]
    codes_b = [0, 4, 1, np.nan, 1, 1]
    ds = make_ds(["gamma", "F0"], vals * 2, ["coulomb"] * 6 + ["bilinear"] * 6, codes + codes_b,
                 errors=[""] * 9 + ["ValueError: x"] + [""] * 2, done=[1] * 10 + [0, 1])
    fig = periodicity_map_figure(ds, annotate=True)
    maps = {c.get_gid(): c for ax in fig.axes for c in ax.collections if str(c.get_gid()).startswith("map:")}
    assert set(maps) == {"map:coulomb", "map:bilinear"}
    a = np.asarray(maps["map:coulomb"].get_array()).reshape(2, 3)     # (F0, gamma)
    np.testing.assert_array_equal(a, [[1, -2, -1], [2, 3, 16]])
    b = np.asarray(maps["map:bilinear"].get_array()).reshape(2, 3)
    np.testing.assert_array_equal(b, [[0, 1, NOT_RUN], [4, FAILED, 1]])
    # one distinct colour per code, and the colour bar names every class present
    rgba = maps["map:coulomb"].to_rgba(a.ravel())
    assert len({tuple(np.round(c, 4)) for c in rgba}) == 6
    np.testing.assert_allclose(maps["map:bilinear"].to_rgba(np.array([-2, FAILED])),
                               [to_rgba(CODE_COLORS[-2]), to_rgba(CODE_COLORS[FAILED])])
    bar = fig.axes[-1]
    names = [t.get_text() for t in bar.get_yticklabels()]
    assert names == ["not run", "failed", "chaos", "quasi-periodic", "nonperiodic", "P1", "P2", "P3", "P4", "P16"]
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert sorted(texts) == sorted(["P1", "chaos", "QP", "P2", "P3", "P16"])


def test_periodicity_map_needs_two_fields():
    ds = make_ds(["gamma"], [1.0, 2.0], ["coulomb"] * 2, [1, 1])
    with pytest.raises(ValueError, match="two fields"):
        periodicity_map_figure(ds)


# --------------------------------------------------------------------------- case figures


def harmonic_case(periods=10, S=50, sub=False, w=OMEGA):
    """History of x1 = gap (0.2 + 2 cos wt + 0.5 cos 2wt [+ 0.8 cos wt/2]) and its velocity."""
    T = 2 * np.pi / w
    t = 3 * T + np.arange(periods * S + 1) * T / S
    X = 0.2 + 2 * np.cos(w * t) + 0.5 * np.cos(2 * w * t) + (0.8 * np.cos(w * t / 2) if sub else 0)
    dX = -2 * w * np.sin(w * t) - w * np.sin(2 * w * t) - (0.4 * w * np.sin(w * t / 2) if sub else 0)
    return t, GAP * X, GAP * dX


def test_case_figure_panels_period1():
    w = 250.0   # not the default 290 rad/s: omega must come from the history's time step
    t, x, v = harmonic_case(w=w)
    ds = make_ds(["gamma"], [1.0], ["bilinear"], [1], history=(t[None], x[None], v[None]),
                 poincare=np.full((1, 6), 2.7 * GAP), vpoincare=np.full((1, 6), 3 * GAP * w), lyapunov=[-0.45],
                 study={"base": {"model": "blade_pair"}})
    fig = case_figure(ds, 0)
    ax_t, ax_f, ax_p, ax_ph = fig.axes
    title = fig.get_suptitle()
    assert "bilinear" in title and "\u03b3 = 1" in title and "P1" in title and "-0.45" in title
    # (a) time history against t/T
    (line,) = [ln for ln in ax_t.get_lines() if ln.get_gid() == "history"]
    np.testing.assert_allclose(line.get_xdata()[[0, -1]], [3, 13])
    np.testing.assert_allclose(line.get_ydata(), x / GAP)
    # (b) spectrum: harmonics 1 (amplitude 2) and 2 (0.5), peak at f/f_e = 1, mean left out
    (spec,) = [c for c in ax_f.collections if c.get_gid() == "spectrum"]
    segs = np.array([s[:, :] for s in spec.get_segments()])
    ratio, amp = segs[:, 0, 0], segs[:, 1, 1]
    assert ratio[np.argmax(amp)] == pytest.approx(1.0)
    assert amp.max() == pytest.approx(2.0, rel=1e-6)
    assert amp[np.isclose(ratio, 2)][0] == pytest.approx(0.5, rel=1e-6)
    assert ratio.min() > 0 and ratio.max() <= 4 + 1e-9
    # (c) Poincare map in nondimensional units: X1, X1' = vx1 / (gap omega)
    np.testing.assert_allclose(scatter(ax_p, "poincare"), np.column_stack([np.full(6, 2.7), np.full(6, 3.0)]))
    # (d) phase portrait: X1' = dX1/dtau
    (ph,) = [ln for ln in ax_ph.get_lines() if ln.get_gid() == "phase"]
    np.testing.assert_allclose(ph.get_ydata(), v / (GAP * w))


def test_case_spectrum_shows_subharmonic_of_period2():
    t, x, v = harmonic_case(sub=True)
    ds = make_ds(["gamma"], [5.3], ["coulomb"], [2], history=(t[None], x[None], v[None]))
    ax_f = case_figure(ds, 0).axes[1]
    (spec,) = [c for c in ax_f.collections if c.get_gid() == "spectrum"]
    segs = np.array(spec.get_segments())
    ratio, amp = segs[:, 0, 0], segs[:, 1, 1]
    assert amp[np.isclose(ratio, 0.5)][0] == pytest.approx(0.8, rel=1e-6)
    assert amp[np.isclose(ratio, 1.5)][0] == pytest.approx(0.0, abs=1e-9)


def test_cases_figure_one_row_per_point_and_failed_point():
    t, x, v = harmonic_case()
    T2 = np.stack([t, t]); X2 = np.stack([x, np.full_like(x, np.nan)]); V2 = np.stack([v, np.full_like(v, np.nan)])
    ds = make_ds(["gamma"], [1.0, 8.0], ["bilinear"] * 2, [1, np.nan], history=(T2, X2, V2),
                 errors=["", "RuntimeError: integration failed at t = 1 s (event storm)"],
                 study={"plot": "cases", "cases": [{"gamma": 1}, {"gamma": 8}]})
    fig = cases_figure(ds)
    assert len(fig.axes) == 8
    assert [sf.get_suptitle() for sf in fig.subfigs][1].endswith("failed")
    assert any("event storm" in tx.get_text() for tx in fig.axes[4].texts)
    with pytest.raises(ValueError, match="out of range"):
        case_figure(ds, 2)


def test_case_figure_without_history():
    ds = make_ds(["gamma"], [1.0], ["coulomb"], [1], study={"base": {"model": "blade_pair", "omega": 100.0}})
    fig = case_figure(ds, 0)
    off = scatter(fig.axes[2], "poincare")   # omega from the base config without a history
    np.testing.assert_allclose(off[:, 1], ds.poincare_vx1.values[0] / (GAP * 100.0))
    assert any("history" in tx.get_text() for tx in fig.axes[0].texts)


# --------------------------------------------------------------------------- files and the CLI


def write_result(path, study: Study, outputs):
    """A real result file laid out by :mod:`blademodel.sweep.storage`, filled with ``outputs``."""
    fields, values, laws, _ = points(study)
    run = study.run
    storage.create(path, study_json=study.model_dump_json(), fields=fields, values=values, laws=laws,
                   periods=run.periods, n_state=4,
                   history=run.history_periods * run.steps_per_period + 1 if run.history_periods else 0)
    for i, out in enumerate(outputs):
        if out is not None:
            storage.write_point(path, i, out)
    return path


def fake_point(k, *, pd=None, period=1, samples=4):
    rng = np.random.default_rng(k)
    out = {"poincare_x1": rng.normal(size=samples) * GAP, "poincare_vx1": rng.normal(size=samples) * GAP * OMEGA,
           "length_scale": GAP, "period": period, "motion": period, "lyapunov": -0.4, "events": 10,
           "final_state": np.zeros(4)}
    if pd is not None:
        out.update(P=1.0, P0=2.0, Pd=pd)
    return out


def test_plot_result_bifurcation_and_reduction(tmp_path):
    st = Study(name="g", laws=["coulomb", "bilinear"], base={"model": "blade_pair"},
               sweep={"gamma": {"values": [1, 2, 3]}},
               run={"transient": 1, "periods": 4, "vibration_reduction": True})
    outs = [fake_point(k, pd=10.0 * k) for k in range(5)] + [{"error": "RuntimeError: boom"}]
    path = write_result(tmp_path / "g.nc", st, outs)
    ds = load_result(path)
    fig = bifurcation_figure(ds)
    np.testing.assert_allclose(scatter(fig.axes[0], "poincare")[:, 1], (ds.poincare_x1.values[:3] / GAP).ravel())
    files = plot_result(path, tmp_path / "figs")
    assert [f.name for f in files] == ["g_bifurcation.png", "g_reduction.png"]
    for f in files:
        assert f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and f.stat().st_size > 10_000


def test_plot_cli_writes_pngs_next_to_result(tmp_path, capsys):
    st = Study(name="m", base={"model": "blade_pair", "friction": "bilinear"},
               sweep={"gamma": {"values": [1, 2]}, "F0": {"values": [40, 50, 60]}}, plot="map",
               run={"transient": 1, "periods": 4})
    path = write_result(tmp_path / "m.nc", st, [fake_point(k, period=1 + k % 3) for k in range(5)] + [None])
    code = cli.main(["plot", str(path)])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert out.splitlines() == [str(tmp_path / "m_map.png")]
    assert (tmp_path / "m_map.png").stat().st_size > 10_000
    # a branch's options name themselves and their values on a sweep's result, which draws neither
    assert cli.main(["plot", str(path), "--quantity", "section", "--state", "x*"]) == 2
    assert "--state 'x*', --quantity 'section': only a branch file" in capsys.readouterr().err


def test_plot_cli_cases_one_figure_per_law(tmp_path, capsys):
    st = Study(name="c", base={"model": "blade_pair"}, laws=["coulomb", "bilinear"], cases=[{"gamma": 1}],
               plot="cases", run={"transient": 1, "periods": 4, "history_periods": 2, "steps_per_period": 10})
    outs = []
    for k in range(2):
        o = fake_point(k)
        t, x, v = harmonic_case(periods=2, S=10)
        o.update(history_t=t, history_x1=x, history_vx1=v)
        outs.append(o)
    path = write_result(tmp_path / "c.nc", st, outs)
    code = cli.main(["plot", str(path), "--out", str(tmp_path / "o")])
    out, _ = capsys.readouterr()
    assert code == 0
    assert [p.split("/")[-1] for p in out.splitlines()] == ["c_cases_coulomb.png", "c_cases_bilinear.png"]
    assert all((tmp_path / "o" / n).exists() for n in ("c_cases_coulomb.png", "c_cases_bilinear.png"))


@pytest.mark.parametrize("content", [None, b"not a netcdf file", "plain-netcdf"])
def test_plot_cli_bad_file(tmp_path, capsys, content):
    path = tmp_path / "r.nc"
    if content == "plain-netcdf":
        xr.Dataset({"a": ("x", [1.0])}).to_netcdf(path)
    elif content is not None:
        path.write_bytes(content)
    code = cli.main(["plot", str(path)])
    _, err = capsys.readouterr()
    assert code == 2
    assert err.startswith("error: ") and "Traceback" not in err and str(path) in err
    assert not list(tmp_path.glob("*.png"))


def test_plot_result_nothing_run_yet(tmp_path):
    st = Study(name="e", base={"model": "blade_pair"}, sweep={"gamma": {"values": [1, 2]}},
               run={"transient": 1, "periods": 4})
    path = write_result(tmp_path / "e.nc", st, [None, None])
    with pytest.raises(ValueError, match="no point"):
        plot_result(path, tmp_path)
    assert load_result(path).attrs["study"]["name"] == "e"
