"""Bad input is refused up front with a message naming the file, field or option and its value.

Issue #13, the input-check rows: each test here failed before the check it
covers existed. Most call the command line in-process (``cli.main``) and refuse
before any kernel is compiled, so they cost next to nothing; the few that run
reuse the blade pair's kernels that the rest of the suite compiles anyway.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from blademodel import cli
from blademodel.config import BladePair, BladedDisk, ConfigError, apply_overrides, load_config

ROOT = Path(__file__).resolve().parents[1]
PAIR = str(ROOT / "models" / "blade_pair_bilinear.yaml")


def _main(capsys, argv):
    """``(exit code, stdout, stderr)`` of ``blademodel argv``."""
    code = cli.main(argv)
    out, err = capsys.readouterr()
    return code, out, err


# --- booleans are not numbers ------------------------------------------------------------

@pytest.mark.parametrize("text", ["true", "false", "yes"])
def test_set_boolean_on_a_number_field_is_refused_naming_the_field(capsys, text):
    code, out, err = _main(capsys, ["equations", PAIR, "--set", f"gamma={text}"])
    assert code == 2 and out == ""
    assert "--set: gamma = " in err and "expected a number, got a boolean" in err
    assert "Traceback" not in err


def test_boolean_numbers_are_refused_in_files_nested_values_and_lists(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text("model: blade_pair\nF0: 60\nblade1:\n  m: true\n")
    with pytest.raises(ConfigError, match=r"p.yaml:4: blade1.m = True: expected a number, got a boolean"):
        load_config(path)
    with pytest.raises(ValueError, match="(?s)mistuning.*expected a number, got a boolean"):
        BladedDisk(blades=4, mistuning=[0.0, True, 0.0, 0.0])
    # Numbers, and booleans where a field takes them, still pass.
    assert apply_overrides(BladePair(), {"gamma": "5"}).gamma == 5.0
    assert BladePair(friction="iwan", friction_options={"elements": 3}).friction_options == {"elements": 3}


# --- model files that are not UTF-8 text ---------------------------------------------------

def test_non_utf8_model_file_names_the_file_line_and_byte(capsys, tmp_path):
    path = tmp_path / "latin1.yaml"
    path.write_bytes("model: blade_pair\n# Schaufel f\u00fcr Test\ngamma: 4\n".encode("latin-1"))
    code, out, err = _main(capsys, ["simulate", str(path)])
    assert code == 2 and out == ""
    assert f"error: {path}:2: not UTF-8 text (byte 0xfc at offset" in err and "Traceback" not in err


def test_binary_model_file_names_the_file(capsys, tmp_path):
    path = tmp_path / "model.yaml"
    path.write_bytes(b"\x7fELF\x02\x01\x01\x00" + bytes(range(256)))
    code, out, err = _main(capsys, ["equations", str(path)])
    assert code == 2 and out == ""
    assert f"error: {path}: not a text file" in err
