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
from blademodel.config import BladedDisk, ConfigError, apply_overrides, load_config
from blademodel.zheng2022 import BladePair

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


# --- runs whose P_d is undefined are kept --------------------------------------------------
RUN = ["--transient", "2", "--periods", "2", "--steps-per-period", "400"]


def _strict_json(text: str) -> dict:
    """Parse JSON as the standard has it: ``NaN`` and ``Infinity`` are errors."""
    def refuse(name):
        raise ValueError(f"invalid JSON constant {name}")
    return json.loads(text, parse_constant=refuse)


@pytest.mark.parametrize("setting, reason", [
    ("F0=0", "P0 = 0.0: the reference system does not move"),           # no force at all
    ("m=1e300", "P0 = 0.0: the reference system does not move"),         # a motion below float64's range
])
def test_undefined_pd_keeps_the_run_and_says_why(capsys, tmp_path, setting, reason):
    out = tmp_path / "r.npz"
    code, stdout, err = _main(capsys, ["simulate", PAIR, *RUN, "--set", setting, "--json", "--out", str(out)])
    assert code == 0, err
    rep = _strict_json(stdout)
    assert rep["Pd"] is None and reason in rep["undefined"]["Pd"] and rep["status"] == "done"
    assert len(rep["poincare"]["X1"]) == 2
    import numpy as np
    saved = np.load(out)
    assert saved["y"].shape == (2 * 400 + 1, 9) and _strict_json(str(saved["report"])) == rep
    code, stdout, _ = _main(capsys, ["simulate", PAIR, *RUN, "--set", setting])
    assert code == 0 and f"P_d: undefined: {reason}" in stdout


def test_json_of_a_result_with_overflowing_mean_squares_is_valid_json(capsys):
    # F0 = 1e200: the states stay finite (x ~ 1e193) but their squares overflow, so P = P0 = inf
    # and P_d = inf / inf used to be printed as NaN.
    code, stdout, err = _main(capsys, ["simulate", PAIR, *RUN, "--set", "F0=1e200", "--json"])
    assert code == 0, err
    assert "NaN" not in stdout and "Infinity" not in stdout
    rep = _strict_json(stdout)
    assert rep["Pd"] is None and "P = inf, P0 = inf" in rep["undefined"]["Pd"]
    assert "RuntimeWarning" not in err


def test_finite_json_replaces_every_non_finite_number_and_lists_it():
    import numpy as np
    from blademodel.commands.jsonout import dumps
    rep = {"a": float("nan"), "b": {"c": [1.0, float("inf"), np.float64(-np.inf)]}, "d": np.array([2.0, np.nan]),
           "e": np.int64(3), "Pd": None}
    out = _strict_json(dumps(rep, {"Pd": "no contacts"}))
    assert out == {"a": None, "b": {"c": [1.0, None, None]}, "d": [2.0, None], "e": 3, "Pd": None,
                   "undefined": {"Pd": "no contacts", "a": "not a finite number (nan)",
                                 "b.c.1": "not a finite number (inf)", "b.c.2": "not a finite number (-inf)",
                                 "d.1": "not a finite number (nan)"}}
    assert "undefined" not in _strict_json(dumps({"x": 1.5}))


# --- --out is checked before anything is computed ---------------------------------------------

@pytest.fixture
def no_run(monkeypatch):
    """Make ``simulate`` fail the test if the command gets as far as running."""
    import blademodel.commands.simulate as cmd

    def ran(*args, **kwargs):
        raise AssertionError("the command started the run before refusing its input")
    monkeypatch.setattr(cmd, "simulate", ran)


def _read_only_folder(tmp_path) -> Path:
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    import os
    if not os.access(folder, os.W_OK):
        return folder
    if Path("/sys").is_dir():  # root writes anywhere chmod forbids; sysfs refuses new files even to root
        return Path("/sys")
    pytest.skip("no read-only folder available")


@pytest.mark.parametrize("case", ["missing folder", "read-only folder", "wrong suffix", "a folder", "under a file"])
def test_bad_out_is_refused_before_the_run_with_exit_2(capsys, tmp_path, no_run, case):
    (tmp_path / "plain").write_text("x")
    out, needle = {
        "missing folder": (tmp_path / "nope" / "r.npz", "does not exist; create it first"),
        "read-only folder": (_read_only_folder(tmp_path) / "r.npz", "cannot write in folder"),
        "wrong suffix": (tmp_path / "x.txt", "the result is a NumPy .npz archive; give a file name ending in .npz"),
        "a folder": (tmp_path, "give a file name ending in .npz"),
        "under a file": (tmp_path / "plain" / "r.npz", "is not a folder"),
    }[case]
    before = sorted(p.name for p in tmp_path.rglob("*"))
    code, stdout, err = _main(capsys, ["simulate", PAIR, "--out", str(out)])
    assert code == 2 and stdout == ""
    assert err.startswith(f"error: --out '{out}': ") and needle in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.rglob("*")) == before   # nothing written (no x.txt.npz)


# --- run length and memory limits, checked up front ------------------------------------------

@pytest.mark.parametrize("argv, needle", [
    (["--transient", str(10 ** 23)], "--transient 100000000000000000000000, --periods 100, --steps-per-period 1000: "
                                     "1e+26 RK4 steps in all, more than a run takes (2**53"),
    (["--steps-per-period", str(10 ** 7)], "the run would keep 1000000001 records of 9 states (96.9 GiB), more than "
                                           "the limit of 2 GiB ($BLADEMODEL_MAX_RECORD_BYTES); record every 49"),
    (["--steps-per-period", str(10 ** 8), "--record-every", str(10 ** 8)],
     "--steps-per-period 100000000: one period of the P_d reference run"),
])
def test_run_limits_are_checked_before_the_run(capsys, no_run, argv, needle):
    code, stdout, err = _main(capsys, ["simulate", PAIR, *argv])
    assert code == 2 and stdout == ""
    assert needle in err and "Traceback" not in err


def test_run_limits_of_the_python_api_come_before_compiling(monkeypatch):
    import importlib
    sim = importlib.import_module("blademodel.numeric.simulate")   # the package exports a function of that name
    from blademodel.numeric.limits import RunTooLargeError

    def compiled(*args, **kwargs):
        raise AssertionError("the kernel was set up before the settings were checked")
    monkeypatch.setattr(sim, "make_integrator", compiled)
    model = BladePair().build()
    with pytest.raises(RunTooLargeError, match=r"1e\+23 RK4 steps in all"):
        sim.simulate(model, transient=1e23, periods=1, steps_per_period=1)
    with pytest.raises(ValueError, match="periods = inf must be an integer >= 1"):
        sim.simulate(model, periods=float("inf"))
    with pytest.raises(ValueError, match="record_every = True must be an integer >= 1"):
        sim.simulate(model, record_every=True)
    from blademodel.numeric.integrator import check_settings
    with pytest.raises(ValueError, match="steps_per_period = inf must be an integer >= 1"):
        check_settings(float("inf"), 1e-10, 100)
    with pytest.raises(ValueError, match="event_tol = nan must be a positive number"):
        check_settings(1000, float("nan"), 100)
    monkeypatch.setenv("BLADEMODEL_MAX_RECORD_BYTES", "1e6")
    with pytest.raises(RunTooLargeError, match=r"more than the limit of 977 KiB"):
        sim.simulate(model, periods=100)
    monkeypatch.setenv("BLADEMODEL_MAX_RECORD_BYTES", "lots")
    with pytest.raises(ValueError, match="BLADEMODEL_MAX_RECORD_BYTES = 'lots' must be a positive number"):
        sim.simulate(model, periods=1)


# --- the integrators' advance validates its arguments ------------------------------------------

def _bad_advance_calls(integ, good_mode, bad_modes):
    """``(kwargs, message)`` pairs of ``advance`` calls the kernel must never see."""
    import numpy as np
    n = integ.n_state
    y = integ.initial_state()
    calls = [(dict(y=y, mode=m), msg) for m, msg in bad_modes]
    calls += [
        (dict(y=y[:-1].copy(), mode=good_mode), f"y must be a writable C-contiguous float64 array of shape ({n},)"),
        (dict(y=np.zeros(n, dtype=np.float32), mode=good_mode), "got a float32 array"),
        (dict(y=list(y), mode=good_mode), "got list"),
        (dict(y=y, mode=good_mode, end_period=-1), "end_period = -1 must be an integer >= 0"),
        (dict(y=y, mode=good_mode, record_every=0), "record_every = 0 must be an integer >= 1"),
        (dict(y=y, mode=good_mode, poincare=np.empty((1, n))), f"poincare must be a writable C-contiguous float64 "
                                                               f"array of shape (>= 2, {n})"),
        (dict(y=y, mode=good_mode, counters=np.zeros(3, dtype=np.int64)), "counters must be"),
        (dict(y=y, mode=good_mode, record=integ.record_buffer(5)[:2]), "record must be a tuple of 3 arrays"),
        (dict(y=y, mode=good_mode, record=(np.empty(5), np.empty((4, n)), integ.record_buffer(5)[2])),
         "record[1] must be"),
    ]
    return calls


def _assert_refused(integ, calls):
    import numpy as np
    for kwargs, msg in calls:
        y0 = kwargs["y"].copy() if isinstance(kwargs["y"], np.ndarray) else None
        args = dict(start_period=0, end_period=2)
        args.update({k: v for k, v in kwargs.items() if k in ("start_period", "end_period")})
        rest = {k: v for k, v in kwargs.items() if k not in ("y", "mode", "start_period", "end_period")}
        with pytest.raises(ValueError, match=r"^advance: ") as info:
            integ.advance(kwargs["y"], kwargs["mode"], args["start_period"], args["end_period"], **rest)
        assert msg in str(info.value), (msg, str(info.value))
        if y0 is not None:
            assert np.array_equal(kwargs["y"], y0)   # nothing was integrated


def test_hybrid_integrator_advance_refuses_bad_arguments():
    import numpy as np
    from blademodel.numeric import HybridIntegrator
    integ = HybridIntegrator(BladePair(friction="bilinear").build(), steps_per_period=400)
    modes = integ.mode_names
    bad = [(len(modes), f"mode = {len(modes)} is not a mode number (0..{len(modes) - 1}: {', '.join(modes)})"),
           (-1, "mode = -1 is not a mode number"), (True, "mode = True is not a mode number"),
           (np.array([0, 0]), "is not a mode number")]
    _assert_refused(integ, _bad_advance_calls(integ, 0, bad))
    y = integ.initial_state()               # a good call still runs
    status, mode, t = integ.advance(y, integ.mode_of(y), 0, 2)
    assert status == 0 and t == pytest.approx(2 * integ.period)


def test_a_run_recorded_from_period_0_that_starts_later_keeps_its_poincare_samples_in_bounds():
    """``n_transient = 0`` with a later start: the Poincare array ``advance`` makes for itself has a row for every
    period from 0 (the kernel writes period ``k``'s sample in row ``k - n_transient``). It was sized from the start
    period, 0 being taken for 'not given', and the kernel wrote past its end: at a start of 2e7 the process
    died (segmentation fault). Run in a child process, which such a write kills."""
    import subprocess
    import sys
    code = ("import numpy as np\n"
            "from blademodel.numeric import HybridIntegrator\n"
            "from blademodel.zheng2022 import BladePair\n"
            "integ = HybridIntegrator(BladePair(friction='bilinear').build(), steps_per_period=400)\n"
            "a = integ.initial_state()\n"
            "b = a.copy()\n"
            "m = integ.mode_of(a)\n"
            "ra = integ.advance(a, m, 2 * 10**7, 2 * 10**7 + 1, n_transient=0)\n"
            "rb = integ.advance(b, m, 2 * 10**7, 2 * 10**7 + 1)\n"
            "print(ra == rb and bool(np.array_equal(a, b)))\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.strip() == "True"

@pytest.mark.slow   # a cold compile of a ring kernel (~50 s in CI); the product kernel's checks run by default
def test_contact_integrator_advance_refuses_bad_arguments():
    import numpy as np
    from blademodel.numeric import ContactIntegrator
    integ = ContactIntegrator(BladedDisk(blades=4, engine_order=1).build())
    modes = integ.meta["contact_modes"][0]
    good = np.zeros(4, dtype=np.int64)
    bad = [(np.array([0, 0, len(modes), 0]), f"mode[2] = {len(modes)} is not a mode of contact "),
           (np.array([0, -1, 0, 0]), "mode[1] = -1 is not a mode of contact"),
           (np.zeros(3, dtype=np.int64), "mode must hold one integer per contact (4)"),
           (np.zeros(4), "mode must hold one integer per contact (4)")]
    calls = _bad_advance_calls(integ, good, bad)
    calls.append((dict(y=integ.initial_state(), mode=good, stats=np.zeros(0)), "stats must be"))
    _assert_refused(integ, calls)
    y = integ.initial_state()
    status, cm, t = integ.advance(y, integ.mode_of(y), 0, 2)
    assert status == 0 and t == pytest.approx(2 * integ.period)


# --- friction laws are checked against the interface before any code is generated -------------
from dataclasses import dataclass, field  # noqa: E402

import sympy as sp  # noqa: E402

from blademodel.components.friction import Candidate, FrictionLaw, Guard  # noqa: E402
from blademodel.components.friction.validation import FrictionLawError, check_law  # noqa: E402
from blademodel.components.parameter import Number, as_param  # noqa: E402


@dataclass(frozen=True)
class SlideLaw(FrictionLaw):
    """A well-formed one-mode law (kinetic friction only); the broken laws below each change one thing."""

    mu: Number = 0.5
    _p: dict = field(init=False, repr=False, compare=False)
    modes = ("slide",)

    def __post_init__(self):
        object.__setattr__(self, "_p", {"mu": as_param(self.mu, "mu", field="friction: mu", minimum=0.0)})

    def parameters(self):
        return dict(self._p)

    def force(self, mode, ctx):
        return ctx.params["mu"] * ctx.N * sp.sign(ctx.v)

    def guards(self, mode, ctx):
        return [Guard(ctx.v, 0, [Candidate("slide")], "reverse")]

    def entry(self, ctx):
        return [Candidate("slide")]


class NoModesLaw(SlideLaw):
    modes = ()

    def entry(self, ctx):
        return [Candidate("open")]


class ForceNoneLaw(SlideLaw):
    def force(self, mode, ctx):
        return None


class UnknownModeLaw(SlideLaw):
    def guards(self, mode, ctx):
        return [Guard(ctx.v, 0, [Candidate("stick")], "v=0")]


class UnknownStateLaw(SlideLaw):
    def exit_reset(self, ctx):
        return {"z": sp.Integer(0)}


class BadDirectionLaw(SlideLaw):
    def guards(self, mode, ctx):
        return [Guard(ctx.v, 2, [Candidate("slide")])]


class RaisingLaw(SlideLaw):
    def rates(self, mode, ctx):
        return {"z": ctx.states["z"]}


class NoGuardsLaw(SlideLaw):
    def guards(self, mode, ctx):
        pass


class GeneratorLaw(SlideLaw):
    """Iterables other than lists are fine: the symbolic layer takes ``list(...)`` of them."""

    def guards(self, mode, ctx):
        yield Guard(ctx.v, 0, (Candidate("slide"),), "reverse")


class NoEntryLaw(SlideLaw):
    def entry(self, ctx):
        return []


class AbstractLaw(FrictionLaw):
    modes = ("slide",)

    def parameters(self):
        return {}


BROKEN = {
    "NoModesLaw": "modes = (): a law needs at least one mode of the closed contact (e.g. modes = ('slip',)); "
                  "'open' is added by the contact",
    "ForceNoneLaw": "force('slide', ctx) returned None; expected a SymPy expression, a number or STICK",
    "UnknownModeLaw": "guards('slide', ctx)[0].candidates[0] names mode 'stick', which is not among its modes "
                      "('open', 'slide')",
    "UnknownStateLaw": "exit_reset(ctx) names state 'z', which is not among its states ()",
    "BadDirectionLaw": "guards('slide', ctx)[0].direction = 2 must be -1, 0 or +1",
    "RaisingLaw": "rates('slide', ctx) raised KeyError: 'z'",
    "NoGuardsLaw": "guards('slide', ctx) returned None; expected a list of Guard",
    "NoEntryLaw": "entry(ctx) returned no Candidate; expected at least one (the last unconditional)",
}


def test_a_well_formed_law_passes_and_the_built_in_laws_too():
    assert isinstance(check_law(SlideLaw()), SlideLaw)
    assert isinstance(check_law(GeneratorLaw()), GeneratorLaw)
    for law in ("coulomb", "bilinear", "none", "iwan"):
        BladePair(friction=law).build()


@pytest.mark.parametrize("name", sorted(BROKEN))
def test_a_broken_law_is_refused_naming_the_law_and_what_is_wrong(name):
    with pytest.raises(FrictionLawError) as info:
        BladePair(friction=f"test_input_checks:{name}").build()
    assert str(info.value) == f"contact c: friction law test_input_checks:{name}: {BROKEN[name]}"


def test_an_abstract_law_class_is_refused_by_name():
    with pytest.raises(ValueError, match=r"test_input_checks:AbstractLaw.*does not implement entry, force, guards"):
        BladePair(friction="test_input_checks:AbstractLaw")


@pytest.mark.parametrize("name", ["NoModesLaw", "ForceNoneLaw"])
def test_cli_refuses_a_broken_law_before_writing_to_the_kernel_cache(capsys, tmp_path, monkeypatch, name):
    cache = tmp_path / "cache"
    monkeypatch.setenv("BLADEMODEL_CACHE_DIR", str(cache))
    path = tmp_path / "p.yaml"
    path.write_text(f"model: blade_pair\nfriction: test_input_checks:{name}\n")
    for command in (["simulate", str(path), *RUN], ["simulate", str(path), *RUN, "--kernel", "contact"],
                    ["equations", str(path)]):
        code, out, err = _main(capsys, command)
        assert code == 2 and out == ""
        assert err == f"error: {path}: contact c: friction law test_input_checks:{name}: {BROKEN[name]}\n"
    assert not cache.exists() or not any(cache.iterdir())


@pytest.mark.parametrize("case", ["read-only folder", "wrong suffix"])
def test_sweep_out_is_checked_before_any_point(capsys, tmp_path, monkeypatch, case):
    import blademodel.commands.sweep as cmd

    def ran(*args, **kwargs):
        raise AssertionError("the sweep started before its --out was checked")
    monkeypatch.setattr(cmd, "run_study", ran)
    out, needle = {"read-only folder": (_read_only_folder(tmp_path) / "new" / "s.nc", "cannot write in folder"),
                   "wrong suffix": (tmp_path / "s.txt", "the result is a NetCDF file; give a file name ending in .nc"),
                   }[case]
    code, stdout, err = _main(capsys, ["sweep", str(ROOT / "models" / "studies" / "fig06.yaml"), "--out", str(out)])
    assert code == 2 and stdout == "" and needle in err and "Traceback" not in err
    assert not out.exists()


def test_a_negative_number_in_exponent_notation_is_read_as_the_option_s_value():
    """argparse before Python 3.12 takes ``-1e-5`` after an option for an option of its own; the command line
    attaches it to the option before parsing, and leaves ``--`` and ``NAME=VALUE`` tokens as they are."""
    assert cli._negative_values_attached(["continue", "m.yaml", "--to", "-1e-5", "--from", "-2.5E+3", "--", "-1e-3",
                                          "--set", "gap=-1e-5", "--period", "2"]) == \
        ["continue", "m.yaml", "--to=-1e-5", "--from=-2.5E+3", "--", "-1e-3", "--set", "gap=-1e-5", "--period", "2"]
    args = cli.build_parser().parse_args(cli._negative_values_attached(
        ["continue", "m.yaml", "--param", "gap", "--from", "1e-5", "--to", "-1e-5"]))
    assert args.start == 1e-5 and args.stop == -1e-5

