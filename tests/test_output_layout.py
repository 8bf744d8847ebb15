"""One output layout: ``sweep`` and ``reproduce`` write ``out/<name>/<name>.nc`` with the figures beside it."""

from pathlib import Path

from blademodel.cli import main
from blademodel.commands.sweep import default_out
from sweep_tools import TINY, write_study


def test_sweep_writes_its_data_and_figures_in_the_studys_folder_and_a_rerun_says_what_it_reuses(
        tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    study = write_study(tmp_path, TINY)
    assert main(["sweep", str(study), "--workers", "1"]) == 0
    folder = Path("out") / "tiny"
    written = sorted(p.name for p in folder.iterdir())
    assert "tiny.nc" in written and any(name.endswith(".png") for name in written)
    assert sorted(p.name for p in Path("out").iterdir()) == ["tiny"]
    capsys.readouterr()
    assert main(["sweep", str(study), "--workers", "1", "--no-plot"]) == 0
    assert "tiny.nc: all 4 points are already done; using them" in capsys.readouterr().err


def test_sweep_and_reproduce_share_the_layout(tmp_path):
    assert default_out(tmp_path, "fig06") == tmp_path / "fig06" / "fig06.nc"
    assert default_out(tmp_path, "fig06", quick=True) == tmp_path / "fig06" / "fig06_quick.nc"
