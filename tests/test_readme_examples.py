"""The README's continuation examples start on orbits of their models (slow: each compiles its model's kernels).

Each ``blademodel continue`` line of the README's examples is run as written, but for a
few points and without its plot. Its first point, read back from the branch file, is then
integrated on the model the line names, built afresh, over the whole model's map (a ring
continued on its reduced map included): it must come back to itself. A README ring was
refused at its first orbit for a stop before anyone ran its line (the turn's check read the
labels' rounding as a change: ``tests/test_discrete_states.py`` checks that fault in the
default run).
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import numpy as np
import pytest

from blademodel.cli import main
from blademodel.config import apply_overrides, load_config
from blademodel.numeric.kernels import make_integrator
from blademodel.orbits import PeriodMap
from blademodel.orbits.branch_file import load_branch

ROOT = Path(__file__).resolve().parents[1]


def _readme_lines() -> list[str]:
    """The README's ``blademodel continue`` example lines, their comments removed."""
    text = (ROOT / "README.md").read_text()
    return [re.sub(r"\s+#.*$", "", m.group(0)).strip()
            for m in re.finditer(r"^blademodel continue [^\n]+$", text, flags=re.M)]


def _name(line: str) -> str:
    """A test id for a README line: its model, settings, field and whether it switches."""
    a = shlex.split(line)[2:]
    sets = [a[i + 1] for i, x in enumerate(a) if x == "--set"]
    return " ".join([Path(a[0]).stem, *sets, _option(a, "--param")] + (["switch"] if "--switch" in a else []))


def _option(argv: list, name: str, default=None):
    return argv[argv.index(name) + 1] if name in argv else default


def _without(argv: list, *names) -> list:
    """``argv`` without the options ``names`` and their values."""
    out, skip = [], False
    for a in argv:
        if skip:
            skip = False
        elif a in names:
            skip = True
        else:
            out.append(a)
    return out


def test_the_readme_has_continuation_examples():
    lines = _readme_lines()
    assert len(lines) >= 6 and all(" --param " in line for line in lines)


@pytest.mark.slow
@pytest.mark.parametrize("line", _readme_lines(), ids=_name)
def test_a_readme_continuation_starts_on_an_orbit_of_its_model(line, tmp_path):
    argv = _without(shlex.split(line)[1:], "--plot", "--out", "--max-points")
    out = tmp_path / "branch.nc"
    assert main([*argv, "--max-points", "3", "--out", str(out)]) == 0
    branch = load_branch(out)
    assert branch.params.size >= 2
    sets = dict(s.split("=", 1) for s in [argv[i + 1] for i, a in enumerate(argv) if a == "--set"])
    model_path = ROOT / argv[1]
    param = _option(argv, "--param")
    cfg = apply_overrides(load_config(model_path), {**sets, param: repr(float(branch.params[0]))})
    ig = make_integrator(cfg.build(), steps_per_period=int(_option(argv, "--steps-per-period", 1000)))
    y = branch.states[0]
    full = np.zeros(ig.n_state)
    full[:y.size] = y
    Py, _ = PeriodMap(ig, branch.periods, "differences", 1)(y, ig.mode_of(full))
    labels = np.asarray(getattr(ig, "discrete_states", ()), dtype=np.int64)
    free = np.setdiff1d(np.arange(y.size), labels)
    scale = np.max(np.abs(branch.states[:, free]), axis=0)
    scale = np.maximum(scale, 1e-3 * scale.max())
    assert np.max(np.abs(Py[free] - y[free]) / scale) < 1e-8
    assert np.array_equal(np.rint(Py[labels]), np.rint(y[labels]))
