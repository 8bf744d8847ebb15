"""Printed equations show subscripts from the parameter names (``cx`` -> ``c_x``), for every shipped model."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import sympy as sp
from sympy.printing.latex import greek_letters_set, modifier_dict

from blademodel.components import Damper, HarmonicForce, Mass, Param, Spring
from blademodel.model import Model
from blademodel.numeric.codegen import generate
from blademodel.symbolic import derive
from blademodel.symbolic.assembly import contact_equations, derive_mode
from blademodel.symbolic.display import equations, latex, latex_contact, pretty, pretty_contact
from blademodel.symbolic.names import display_name, readable_symbols
from blademodel.config import load_model

MODEL_DIR = Path(__file__).resolve().parents[1] / "models"
MODELS = sorted(MODEL_DIR.glob("*.yaml"))


@pytest.mark.parametrize("name, shown", [
    ("cx", "c_x"), ("kd", "k_d"), ("mu", "mu"), ("Delta", "Delta"), ("gamma", "gamma"), ("F0", "F_0"),
    ("kx_2", "k_x,2"), ("Delta_c3", "Delta_c3"), ("kx1", "k_x1"), ("m1", "m_1"), ("phi1", "phi_1"),
    ("F0_m", "F_0,m"), ("kd_c12", "k_d,c12"), ("mu_c12", "mu_c12"), ("nu", "nu"), ("xi_2", "xi_2"),
    ("Ndot_c", "Ndot_c"), ("Qbar_1x", "Qbar_1x"), ("gap", "gap"), ("k", "k"), ("x_m", "x_m"), ("_Q", "_Q"),
])
def test_display_names(name, shown):
    assert display_name(name) == shown


@pytest.mark.parametrize("name, tex", [("cx", "c_{x}"), ("kd", "k_{d}"), ("mu", r"\mu"), ("Delta", r"\Delta"),
                                       ("gamma", r"\gamma"), ("F0", "F_{0}"), ("kx_2", "k_{x,2}"),
                                       ("Delta_c3", r"\Delta_{c3}"), ("kd_c12", "k_{d,c12}")])
def test_display_names_in_latex(name, tex):
    assert sp.latex(sp.Symbol(display_name(name))) == tex


def test_names_that_would_show_alike_keep_their_own():
    a, b, c = sp.symbols("kx2 k_x2 cx")
    sub = readable_symbols([a + b + c])
    assert a not in sub and b not in sub and sub[c] == sp.Symbol("c_x")


def test_generated_code_keeps_the_model_names():
    """The display never renames the symbols the kernels are generated from."""
    m = Mass("1", Param("m", 1.0), dofs=("x",))
    model = Model((m,), (Spring("x1", Param("kx", 4.0)),), (Damper("x1", Param("cx", 0.1)),),
                  (HarmonicForce(m, Param("F0", 1.0), Param("omega", 1.5)),))
    system = derive(model)
    assert "c_x" in pretty(system, unicode=False)
    source, meta = generate(system)
    assert meta["params"][:4] == ["m", "kx", "cx", "F0"] and "c_x" not in source
    eq = equations(system, system.modes[0].name)[0]
    assert sp.Symbol("cx", real=True) in eq.lhs.free_symbols    # the public equations keep the model's symbols


# --- every shipped model ------------------------------------------------------------------------------------

_FUNCTIONS = {"sin", "cos", "tan", "tanh", "exp", "log", "sqrt", "Abs", "sign", "Min", "Max", "Heaviside",
              "mode", "where", "guard", "open", "close", "stick", "slip", "if", "rises", "falls", "through", "crosses",
              "the", "constraint", "force", "which", "holds", "it", "depends", "on", "other", "contacts", "modes",
              "see", "penetration", "closed", "while", "positive", "relative", "velocity", "dr", "dt", "normal",
              "dN", "and", "contact", "bodies", "body", "ground", "friction", "law", "every", "others", "Jenkins",
              "Coulomb", "NoFriction", "v", "t", "constant", "load", "from", "start", "never", "opens"}
_TEX_COMMANDS = {"paragraph", "texttt", "begin", "end", "intertext", "text", "left", "right", "sin", "cos", "tan",
                 "tanh", "exp", "log", "sqrt", "frac", "dot", "ddot", "operatorname", "geq", "leq", "wedge", "vee",
                 "quad", "to", "cdot", "min", "max", "bar", "theta", "mu", "Delta", "delta", "alpha", "beta",
                 "gamma", "omega", "phi", "varphi", "epsilon", "lambda", "sigma", "tau", " ", ",", "{", "}", "_",
                 "textbackslash", "left|", "right|"} | greek_letters_set | {g.capitalize() for g in greek_letters_set}


def _renderings(path: Path):
    """``(label, latex, unicode pretty, ascii pretty)`` of a model's modes, or one mode and one contact."""
    model = load_model(path)
    if len(model.contacts) <= 1:
        system = derive(model)
        yield path.stem, latex(system), pretty(system), pretty(system, unicode=False)
    else:
        first = model.contacts[0]
        system = derive_mode(model, {first.name: first.modes[1], model.contacts[1].name: model.contacts[1].modes[-1]},
                             guards=False)
        yield f"{path.stem} mode", latex(system), pretty(system), pretty(system, unicode=False)
    ce = contact_equations(model, model.contacts[0].name)
    yield f"{path.stem} contact", latex_contact(ce), pretty_contact(ce), pretty_contact(ce, unicode=False)


def _check_latex(tex: str):
    """Braces balance and every identifier outside text is one letter or a known command.

    (SymPy's LaTeX parser needs antlr4, which is not installed: this is the structural check instead.)
    """
    depth = 0
    for ch in tex.replace(r"\{", "").replace(r"\}", ""):
        depth += {"{": 1, "}": -1}.get(ch, 0)
        assert depth >= 0, tex
    assert depth == 0
    assert tex.count(r"\begin{align*}") == tex.count(r"\end{align*}") >= 1
    assert tex.count(r"\left") == tex.count(r"\right")
    body = re.sub(r"\\(paragraph|texttt|text|intertext|begin|end|operatorname)\{[^{}]*(\{[^{}]*\}[^{}]*)*\}", "", tex)
    body = "\n".join(line for line in body.splitlines() if not line.startswith("%"))
    commands = set(re.findall(r"\\([A-Za-z]+)", body))
    assert commands <= _TEX_COMMANDS, commands - _TEX_COMMANDS
    words = set(re.findall(r"(?<![\\A-Za-z])[A-Za-z]{2,}", body))
    assert not words, f"multi-letter identifiers printed as products: {sorted(words)}"


def _check_ascii(text: str):
    """Every identifier is a function name or a display name: a letter, a Greek name or a modified one."""
    lines = text.splitlines()
    kept = [line for line, below in zip(lines, lines[1:] + [""])      # headings name models, modes, contacts
            if not (below.startswith("=") or set(line) <= {"="} or line.startswith("mode "))]
    for token in set(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", "\n".join(kept))):
        head = token.split("_")[0]
        if token in _FUNCTIONS or not head:
            continue
        ok = (len(head) == 1 or head.lower() in greek_letters_set
              or any(head.endswith(m) and len(head) > len(m) for m in modifier_dict))
        assert ok and not re.search(r"[A-Za-z][0-9]", head), token


@pytest.mark.parametrize("path", MODELS, ids=[p.stem for p in MODELS])
def test_every_shipped_model_renders_readably(path):
    for label, tex, uni, ascii_ in _renderings(path):
        _check_latex(tex)
        _check_ascii(ascii_)
        assert not re.search(r"\b(cx|kx|kd|cy|ky|kc)\b", tex + uni + ascii_), label
        if "contact" not in label:
            assert "c_{" in tex or "c " in tex, label     # a damper's coefficient: c_{x} or plain c
            assert r"\dot{x}_{" in tex


def test_the_blade_pair_reads_like_the_paper():
    tex = latex(derive(load_model(MODEL_DIR / "blade_pair_bilinear.yaml")), "stick")
    assert r"m \ddot{x}_{1} + c_{x} \dot{x}_{1} + k_{x} x_{1} &= F_{0}" in tex
    assert r"f_{c} &= k_{d} z" in tex and r"\phi_{1}" in tex and r"\Delta" in tex

