"""The paper wing depends on the framework, never the other way round; the framework finds it as a plugin."""

import ast
from pathlib import Path

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

