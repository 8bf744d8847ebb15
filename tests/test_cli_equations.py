"""The ``blademodel equations`` command and the display of the equations."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest
import sympy as sp
from sympy.physics.vector import dynamicsymbols

from blademodel import cli
from blademodel.config import load_model
from blademodel.symbolic import derive
from blademodel.symbolic.display import definitions, equations, latex, pretty

MODELS = Path(__file__).resolve().parents[1] / "models"
BILINEAR = str(MODELS / "blade_pair_bilinear.yaml")


def run_cli(capsys, *argv):
    code = cli.main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def bilinear_system():
    return derive(load_model(BILINEAR))


def test_equations_prints_every_mode(capsys, bilinear_system):
    code, out, err = run_cli(capsys, "equations", BILINEAR)
    assert code == 0 and err == ""
    names = [m.name for m in bilinear_system.modes]
    assert names == ["open", "stick", "slip+", "slip-"]
    for name in names:
        assert f"mode {name}\n" in out
    assert out.count("N_c = ") == 4 and "z\u0307" in out   # z with a combining dot


def test_equations_one_mode(capsys):
    code, out, _ = run_cli(capsys, "equations", BILINEAR, "--mode", "stick", "--ascii")
    assert code == 0
    assert "mode stick" in out and "mode slip+" not in out and "mode open" not in out
    assert "f_c = k_d*z" in out
    assert "m*x_1''(t) + c_x*x_1'(t) + k_x*x_1" in out      # the paper's left-hand side order


def test_equations_latex(capsys):
    code, out, _ = run_cli(capsys, "equations", BILINEAR, "--latex")
    assert code == 0
    assert out.count(r"\begin{align*}") == 4 == out.count(r"\end{align*}")
    assert r"\texttt{slip+}" in out and r"\ddot{x}_{1}" in out and r"\intertext{where}" in out


def test_equations_with_override(capsys):
    code, out, _ = run_cli(capsys, "equations", BILINEAR, "--set", "friction=coulomb", "--mode", "stick")
    assert code == 0 and "mode stick" in out and "kd" not in out   # Coulomb: no Jenkins state


@pytest.mark.parametrize("argv, needles", [
    (["equations", BILINEAR, "--mode", "glide"], ["no mode 'glide'", "open", "stick", "slip+", "slip-"]),
    (["equations", "no/such/file.yaml"], ["no/such/file.yaml", "cannot read"]),
    (["equations", BILINEAR, "--set", "gamma=-1"], ["gamma = -1", "greater than or equal to 0"]),
    (["equations", BILINEAR, "--set", "gama=1"], ["gama", "unknown field"]),
    (["equations", BILINEAR, "--set", "gamma"], ["NAME=VALUE"]),
])
def test_errors_exit_2_without_traceback(capsys, argv, needles):
    code, out, err = run_cli(capsys, *argv)
    assert code == 2
    assert err.startswith("error: ") and "Traceback" not in err
    for needle in needles:
        assert needle in err, err


def test_bad_config_reports_file_and_line(capsys, tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("model: blade_pair\nm: 0.085\nkx: -5\n")
    code, _, err = run_cli(capsys, "equations", str(path))
    assert code == 2
    assert f"error: {path}:3: kx = -5: Input should be greater than or equal to 0" in err


@pytest.mark.parametrize("text", ["model: blade_pair\nm: [1, 2\n", "model: components\nmasses: []\n"])
def test_subprocess_exits_nonzero_without_traceback(tmp_path, text):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    proc = subprocess.run([sys.executable, "-m", "blademodel", "equations", str(path)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert proc.stderr.startswith(f"error: {path}:")


def test_usage_error_exits_2(capsys):
    with pytest.raises(SystemExit) as info:
        cli.main(["equations"])
    assert info.value.code == 2


def test_missing_command_modules_are_skipped(monkeypatch):
    monkeypatch.setattr(cli, "COMMANDS", ["equations", "does_not_exist_yet"])
    parser = cli.build_parser()
    assert parser.parse_args(["equations", "x.yaml"]).command == "equations"


# --- the displayed equations are the derived ones --------------------------------------
@pytest.mark.parametrize("path", ["blade_pair_coulomb.yaml", "blade_pair_bilinear.yaml",
                                  "blade_pair_general.yaml", "friction_oscillator.yaml"])
def test_displayed_equations_match_accelerations(path):
    """Substituting N_c, f_c of a mode and its accelerations makes every equation hold."""
    system = derive(load_model(MODELS / path))
    t = dynamicsymbols._t
    back = {system.t: t}
    for q, u in zip(system.q, system.u):
        back[q] = dynamicsymbols(q.name)
        back[u] = dynamicsymbols(q.name).diff(t)
    for s in system.s:
        back[s] = dynamicsymbols(s.name)
    for mode in system.modes:
        eqs = equations(system, mode.name)
        defs = definitions(system, mode.name)
        assert len(eqs) == len(system.q)
        contact = {d.lhs: d.rhs for d in defs if d.lhs in set(system.normal_symbols + system.friction_symbols)}
        for i, (eq, q) in enumerate(zip(eqs, system.q)):
            acc = sp.sympify(mode.accelerations[i]).xreplace(back)
            residual = (eq.lhs - eq.rhs).xreplace(contact).subs(dynamicsymbols(q.name).diff(t, 2), acc)
            assert sp.simplify(residual) == 0, (path, mode.name, q)
        rates = [d for d in defs if d.lhs.has(*[dynamicsymbols(s.name) for s in system.s])] if system.s else []
        assert len(rates) == len(system.s)


def test_stick_force_of_equal_masses_is_eq_9(bilinear_system):
    """The Coulomb stick force displayed is the paper's Eq. 9."""
    system = derive(load_model(MODELS / "blade_pair_coulomb.yaml"))
    f = next(d.rhs for d in definitions(system, "stick") if d.lhs.name == "f_c")
    S = {n: sp.Symbol(n, real=True) for n in ("F0", "omega", "phi1", "phi2", "alpha", "beta", "cx", "cy",
                                               "kx", "ky")}
    t = dynamicsymbols._t
    x1, y1, x2, y2 = dynamicsymbols("x1 y1 x2 y2")
    Q1 = S["F0"] * sp.sin(S["omega"] * t + S["phi1"])
    Q2 = S["F0"] * sp.sin(S["omega"] * t + S["phi2"])
    a, b = S["alpha"], S["beta"]
    eq9 = sp.Rational(1, 2) * ((Q1 - Q2) * (sp.cos(a) * sp.cos(b) + sp.sin(a) * sp.sin(b))
                               - S["cx"] * (x1.diff(t) - x2.diff(t)) * sp.cos(a)
                               - S["cy"] * (y1.diff(t) - y2.diff(t)) * sp.sin(a)
                               - S["kx"] * (x1 - x2) * sp.cos(a) - S["ky"] * (y1 - y2) * sp.sin(a))
    assert sp.simplify(f - eq9) == 0


def test_pretty_and_latex_of_the_row_head_every_mode():
    system = derive(load_model(MODELS / "blade_row_3.yaml"))
    text = pretty(system, unicode=False)
    tex = latex(system)
    for m in system.modes:
        assert f"blade_row_3: mode {m.name}\n" in text
        assert rf"\paragraph{{Mode \texttt{{{m.name}}}}}" in tex
    with pytest.raises(KeyError, match="c12=open,c23=open"):
        pretty(system, "stick")


# --- several contacts: one mode at a time, or one contact ----------------------------------------
ROW = str(MODELS / "blade_row_3.yaml")
RING = str(MODELS / "bladed_disk_24.yaml")
COULOMB = str(MODELS / "blade_pair_coulomb.yaml")


def test_several_contacts_show_the_open_mode_and_how_to_ask_for_others(capsys):
    code, out, err = run_cli(capsys, "equations", ROW, "--ascii")
    assert code == 0 and err == ""
    assert out.startswith("blade_row_3: mode open (every contact)\n")
    assert out.count("blade_row_3: mode") == 1                     # nothing enumerated
    assert "N_c12" not in out and "f_c23" not in out                # every contact open
    hint = out.strip().splitlines()[-1]
    assert "16 mode combinations" in hint
    assert "--mode c12=stick,c23=stick" in hint and "--contact c12" in hint


def test_mode_assignment(capsys):
    code, out, err = run_cli(capsys, "equations", ROW, "--mode", "c12=stick,c23=slip+", "--ascii")
    assert code == 0 and err == ""
    assert out.startswith("blade_row_3: mode c12=stick,c23=slip+\n")
    assert "--mode" not in out                                       # no hint when a mode is asked for
    for needle in ("N_c12 = k*", "f_c12 = ", "N_c23 = k*", "f_c23 = k_d*z", "z'(t) = "):
        assert needle in out, needle
    assert "m*x_3''(t) + c_x*x_3'(t) + k_x*x_3" in out


def test_mode_assignment_leaves_other_contacts_open(capsys):
    code, out, _ = run_cli(capsys, "equations", ROW, "--mode", "c12=stick", "--ascii")
    assert code == 0
    assert out.startswith("blade_row_3: mode c12=stick (others open)\n")
    assert "f_c12 = " in out and "N_c23" not in out and "z'(t)" not in out


def test_mode_assignment_latex(capsys):
    code, out, _ = run_cli(capsys, "equations", ROW, "--mode", "c12=stick", "--latex")
    assert code == 0
    assert out.count(r"\begin{align*}") == 1 == out.count(r"\end{align*}")
    assert r"\texttt{c12=stick (others open)}" in out and r"\intertext{where}" in out


def test_open_mode_latex_has_the_hint_as_a_comment(capsys):
    code, out, _ = run_cli(capsys, "equations", ROW, "--latex")
    assert code == 0
    assert out.count(r"\begin{align*}") == 1
    assert out.strip().splitlines()[-1].startswith("% Only the mode with every contact open is shown")


def test_mode_open_is_every_contact_open(capsys):
    code, out, _ = run_cli(capsys, "equations", ROW, "--mode", "open", "--ascii")
    assert code == 0 and out.startswith("blade_row_3: mode open (every contact)\n") and "--contact" not in out


def test_one_contact_model_takes_a_contact_assignment_too(capsys):
    _, by_name, _ = run_cli(capsys, "equations", COULOMB, "--mode", "stick")
    code, by_assignment, _ = run_cli(capsys, "equations", COULOMB, "--mode", "c=stick")
    assert code == 0 and by_assignment == by_name


def test_contact_equations(capsys):
    code, out, err = run_cli(capsys, "equations", ROW, "--contact", "c23", "--ascii")
    assert code == 0 and err == ""
    assert out.startswith("blade_row_3: contact c23 (bodies 2 and 3; friction law Jenkins)\n")
    for mode in ("open", "stick", "slip+", "slip-"):
        assert f"\nmode {mode}\n" in out
    for needle in ("delta_c23 = ", "r_c23 = ", "v_c23 = ", "N_c23 = delta_c23*k", "Ndot_c23 = ",
                   "f_c23 = k_d*z", "z'(t) = v_c23", "guard close: delta_c23   rises through 0",
                   "guard stick->slip+: N_c23*mu - k_d*z   falls through 0", "-> stick, z = 0"):
        assert needle in out, needle
    assert "x_1" not in out                                  # only the contact's own bodies


def test_contact_equations_of_a_coulomb_stick(capsys):
    code, out, _ = run_cli(capsys, "equations", ROW, "--contact", "c12")
    assert code == 0
    assert "f_c12: the stick constraint force, which holds v̇_c12 = 0" in out
    assert "→ stick if N_c12⋅μ - │f_c12│ ≥ 0" in out


def test_contact_equations_latex(capsys):
    code, out, _ = run_cli(capsys, "equations", ROW, "--contact", "c12", "--latex")
    assert code == 0
    assert out.startswith(r"\paragraph{Contact \texttt{c12}}")
    assert out.count(r"\begin{align*}") == 1 and out.count(r"\intertext{mode") == 4
    assert r"\texttt{stick->slip+} &: " in out


def test_contact_equations_of_a_one_contact_model(capsys):
    code, out, _ = run_cli(capsys, "equations", BILINEAR, "--contact", "c", "--ascii")
    assert code == 0 and "contact c (bodies 1 and 2; friction law Jenkins)" in out


@pytest.mark.parametrize("argv, needles", [
    (["--mode", "c99=stick"], ["--mode c99=stick", "no contact 'c99'", "contacts are c12, c23"]),
    (["--mode", "c12=glide"], ["contact c12 has no mode 'glide'", "its modes are open, stick, slip+, slip-"]),
    (["--mode", "c12=stick,c23=slide"], ["contact c23 has no mode 'slide'", "open, stick, slip+, slip-"]),
    (["--mode", "stick"], ["'stick' is not CONTACT=MODE", "contacts are c12, c23"]),
    (["--mode", "c12=stick,c12=open"], ["contact c12 is named twice"]),
    (["--contact", "c9"], ["no contact 'c9'; contacts are c12, c23"]),
])
def test_mode_and_contact_errors_exit_2(capsys, argv, needles):
    code, out, err = run_cli(capsys, "equations", ROW, *argv)
    assert code == 2 and out == ""
    assert err.startswith("error: ") and "Traceback" not in err
    for needle in needles:
        assert needle in err, err


def test_one_contact_model_errors_name_the_contact(capsys):
    code, _, err = run_cli(capsys, "equations", COULOMB, "--mode", "c1=stick")
    assert code == 2 and "no contact 'c1'; contacts are c" in err


def test_mode_and_contact_exclude_each_other(capsys):
    with pytest.raises(SystemExit) as info:
        cli.main(["equations", ROW, "--mode", "open", "--contact", "c12"])
    assert info.value.code == 2
    assert "not allowed with" in capsys.readouterr().err


def test_bladed_disk_mode_answers_in_seconds(capsys):
    t0 = time.perf_counter()
    code, out, err = run_cli(capsys, "equations", RING, "--mode", "c1=stick,c2=stick", "--ascii")
    elapsed = time.perf_counter() - t0
    assert code == 0 and err == ""
    assert elapsed < 10, elapsed
    assert out.splitlines()[0].endswith("mode c1=stick,c2=stick (others open)")
    assert out.count("''(t)") == 48                       # one equation per coordinate
    assert "f_c1 = " in out and "f_c2 = " in out and "f_c3" not in out


def test_bladed_disk_without_flags_shows_one_mode(capsys):
    code, out, _ = run_cli(capsys, "equations", RING, "--ascii")
    assert code == 0
    assert out.count(": mode ") == 1 and "281474976710656 mode combinations" in out
    assert "--mode c1=stick,c2=stick" in out and "--contact c1" in out


def test_bladed_disk_contact(capsys):
    code, out, _ = run_cli(capsys, "equations", RING, "--contact", "c24", "--ascii")
    assert code == 0 and "contact c24 (bodies 24 and 1; friction law Coulomb)" in out


def test_ring_all_sticking_is_reported(capsys):
    every = ",".join(f"c{i}=stick" for i in range(1, 25))
    code, _, err = run_cli(capsys, "equations", RING, "--mode", every)
    assert code == 2 and "Traceback" not in err
    assert "cannot all stick rigidly" in err and "not independent" in err
