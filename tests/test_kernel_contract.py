"""The kernel contract: named counters and statuses, the run buffer, a cache that cannot go stale."""

import os
import sys

import numba
import numpy as np
import pytest

from blademodel.config import BladedDisk
from blademodel.numeric import ContactIntegrator, contract, simulate
from blademodel.numeric import contact_kernel
from blademodel.numeric.contact_tables import cached_tables, derive_tables


def test_counter_and_status_names_cover_their_indices():
    idx = sorted(getattr(contract, n) for n in dir(contract) if n.startswith("C_"))
    assert idx == list(range(contract.N_COUNTERS)) == list(range(len(contract.COUNTER_NAMES)))
    assert sorted(getattr(contract, n) for n in dir(contract) if n.startswith("S_")) == list(range(contract.N_STATS))
    codes = sorted(getattr(contract, n) for n in dir(contract) if n.startswith("STATUS_") and n != "STATUS_NAMES")
    assert codes == sorted(contract.STATUS_NAMES)


def test_run_buffer_offsets_are_distinct_and_inside_their_arrays():
    integ = ContactIntegrator(BladedDisk(blades=5, friction="bilinear").build(), check_stability=False)
    I = integ.I
    n, nc = I[contract.H_N], I[contract.H_NC]
    assert (n, nc) == (10, 5)
    for prefix, arr in (("O_", I), ("R_", integ.R), ("F_", integ.WF)):
        offs = sorted(I[getattr(contract, k)] for k in dir(contract) if k.startswith(prefix))
        assert len(set(offs)) == len(offs) and offs[-1] < arr.size
    # the tables read back through the header equal the numeric tables
    o = I[contract.R_INVM]
    assert np.array_equal(integ.R[o:o + n], integ.tables.invm)
    o = I[contract.R_W]
    assert np.array_equal(integ.R[o:o + nc * nc].reshape(nc, nc), integ.tables.W)


def test_an_edited_generated_module_is_never_run(tmp_path, monkeypatch):
    monkeypatch.setenv("BLADEMODEL_CACHE_DIR", str(tmp_path))
    model = BladedDisk(blades=3, friction="none").build()
    contact_kernel._MEMO.clear()
    module, _ = contact_kernel.compile_contact_kernel(model)
    # this cache's file (an identical module may have been loaded from another cache: same text, same name)
    path = tmp_path / os.path.basename(module.__file__)
    text = path.read_text()
    assert path.name == contact_kernel._module_name(text)            # the file is named by its own hash
    with open(path, "a") as fh:
        fh.write("\n# an edit\n")
    contact_kernel._MEMO.clear()
    module2, _ = contact_kernel.compile_contact_kernel(model)
    assert os.path.basename(module2.__file__) == path.name          # regenerated under the same name ...
    assert path.read_text() == text                                 # ... from the source, not the edit


def test_tables_follow_the_component_sources(tmp_path, monkeypatch):
    monkeypatch.setenv("BLADEMODEL_CACHE_DIR", str(tmp_path))
    model = BladedDisk(blades=3).build()
    assert cached_tables(model) == derive_tables(model)
    monkeypatch.setattr("blademodel.numeric.contact_tables._components_version", lambda: "edited")
    names = {p.name for p in tmp_path.iterdir()}
    cached_tables(model)
    assert len({p.name for p in tmp_path.iterdir()} - names) == 1  # a new entry, not the old one


def test_a_friction_problem_left_unresolved_is_a_named_status():
    """With a pivot cap of zero the first friction problem stops the run with its named status."""
    cfg = BladedDisk(blades=4, engine_order=1)
    integ = ContactIntegrator(cfg.build(), max_pivots=0)
    y = integ.initial_state()
    cm = integ.mode_of(y)
    status, cm, t = integ.advance(y, cm, 0, 20)
    assert status == contract.STATUS_FRICTION_UNRESOLVED and t > 0
    r = simulate(cfg.build(), periods=20, raise_on_error=False)
    assert r.status == contract.STATUS_OK and r.counters["friction_pivots"] > 0


def test_internal_functions_are_only_linked_and_entry_points_internalize(tmp_path, monkeypatch):
    """The kernel's functions without a Python wrapper get a code library that is only linked (no module
    optimization, no machine code of their own), an entry point called from Python only one that makes what it
    links internal (blademodel.numeric.code_libraries); the forces are those of the equations."""
    from blademodel.numeric import code_libraries
    if not numba.__version__.startswith(code_libraries.CHECKED_NUMBA):
        pytest.skip(f"Numba {numba.__version__} is not a release the pipelines were checked on: Numba's own run")
    assert code_libraries.SUPPORTED   # a checked release must have what the pipelines replace
    monkeypatch.setenv("BLADEMODEL_CACHE_DIR", str(tmp_path))   # compiled here, not loaded from a cache
    contact_kernel._MEMO.clear()
    # nor taken from a module an earlier test of this process imported (its entry points loaded from that
    # test's cache compile nothing they link); put back after the test
    for name in [m for m in sys.modules if m.startswith("blademodel_generated_")]:
        monkeypatch.delitem(sys.modules, name)
    integ = ContactIntegrator(BladedDisk(blades=3, friction="none").build(), check_stability=False)
    y = integ.initial_state()
    y[0] = 1e-3
    N, f = integ.contact_forces(0.0, y, np.ones(integ.nc, dtype=np.int64))
    contact_kernel._MEMO.clear()

    def library(fn):
        return next(iter(fn.overloads.values())).library
    assert isinstance(library(integ.module.contact_forces), code_libraries.LinkedOnlyLibrary)
    assert isinstance(library(integ.module.forces), code_libraries.EntryPointLibrary)
    t = integ.tables
    delta = [sum(t.cgn[j, k] * y[t.cidx[j, k]] for k in range(4) if t.cidx[j, k] >= 0) - t.cgap[j]
             for j in range(integ.nc)]
    assert np.allclose(N, t.ck * np.array(delta), rtol=1e-14, atol=0.0) and not f.any()
