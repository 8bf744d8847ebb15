"""The paper wing depends on the framework, never the other way round; the framework finds it as a plugin."""

import ast
from pathlib import Path

import numpy as np
import pytest

import blademodel
from blademodel.cli import main
from blademodel.config import load_config
from blademodel.config.kinds import model_kinds

PACKAGE = Path(blademodel.__file__).resolve().parent
WING = "blademodel.zheng2022"


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports_of(path: Path) -> set[str]:
    """Every module an ``import`` or ``from ... import`` statement of ``path`` names (relative ones resolved)."""
    module = _module_name(path)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = package.split(".")
            base = base[:len(base) - node.level + 1] if node.level else []
            target = ".".join(base + ([node.module] if node.module else []))
            found.add(target)
            found |= {f"{target}.{a.name}" for a in node.names}
    return found


MODULES = {_module_name(p): imports_of(p) for p in sorted(PACKAGE.rglob("*.py"))}


def test_the_graph_is_read_correctly():
    """The resolver sees relative imports: the wing's own imports of the framework are found."""
    assert "blademodel.config.kinds" in MODULES["blademodel.zheng2022"]
    assert "blademodel.zheng2022.blade_pair" in MODULES["blademodel.zheng2022"]
    assert "blademodel.sweep.point" in MODULES["blademodel.zheng2022.studies"]


def test_no_framework_module_imports_the_wing():
    offenders = {m: sorted(i for i in imps if i == WING or i.startswith(WING + "."))
                 for m, imps in MODULES.items() if not (m == WING or m.startswith(WING + "."))}
    assert not {m: i for m, i in offenders.items() if i}


def test_the_wing_imports_only_the_framework_and_third_parties():
    framework = {m for m in MODULES if not m.startswith(WING)}
    for m, imps in MODULES.items():
        if m.startswith(WING):
            own = {i for i in imps if i.startswith("blademodel")}
            assert all(i.startswith(WING) or i in framework or i.rpartition(".")[0] in framework for i in own), m


def test_blade_pair_configs_load_through_the_registry():
    from blademodel.zheng2022 import BladePair
    assert model_kinds()["blade_pair"] is BladePair
    cfg = load_config(Path(__file__).resolve().parents[1] / "models" / "blade_pair_bilinear.yaml")
    assert isinstance(cfg, BladePair) and cfg.friction == "bilinear"


def test_reproduce_is_a_command():
    with pytest.raises(SystemExit) as e:
        main(["reproduce", "--help"])
    assert e.value.code == 0


def test_pd_and_sections_of_any_model_follow_one_rule():
    """A components model whose coordinate is ``x_m`` (no ``x1``): a preloaded frictionless wall that never opens
    adds its stiffness and a static offset. P_d and the Poincare samples come from the first mass's coordinate and
    equal the closed forms: mean square ``d^2 + X^2 / 2`` with and without the wall, samples on ``d + X sin(...)``."""
    from blademodel.sweep.point import observed, run_point
    from blademodel.config import config_from_data

    m, k, c, kc, gap, F, w = 1.0, 100.0, 4.0, 100.0, -0.01, 0.1, 9.0
    base = {"model": "components", "name": "wall",
            "parameters": {"omega": w},
            "masses": [{"name": "m", "m": m, "dofs": ["x"]}],
            "springs": [{"a": "x_m", "k": k}], "dampers": [{"a": "x_m", "c": c}],
            "forces": [{"mass": "m", "amplitude": F, "omega": "omega"}],
            "contacts": [{"name": "wall", "bodies": ["m", "ground"], "alpha": 1.5707963267948966, "gap": gap,
                          "k": kc}]}
    assert observed(config_from_data(dict(base)).build()) == ("x_m",)
    run = {"transient": 60, "periods": 20, "steps_per_period": 1000, "event_tol": 1e-10, "lyapunov_periods": 0,
           "vibration_reduction": True, "history_periods": 0}
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
