"""Ctrl-C and SIGTERM are never lost: a swallowed interrupt is raised again between units of work, and one that
arrives while a file is written is raised once the file is complete."""

import os
import signal
import threading
import time

import pytest

from blademodel import interrupts
from blademodel.sweep import Study, run_study
from blademodel.sweep.errors import SweepInterrupted
from sweep_tools import TINY, done_count

pytestmark = pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                                reason="signal handlers are set on the main thread only")


@pytest.fixture(autouse=True)
def sigint_as_from_a_terminal():
    """Python's own SIGINT handler, as in a terminal: a test run started in the background (``nohup``, ``&``, CI)
    inherits SIGINT ignored, and :func:`~blademodel.interrupts.handled` leaves an ignored signal ignored."""
    before = signal.getsignal(signal.SIGINT)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


def _swallowed(sig=signal.SIGINT):
    """A signal whose KeyboardInterrupt is caught and dropped, as compiled code that calls back into Python does."""
    try:
        os.kill(os.getpid(), sig)
        time.sleep(5)   # the handler raises here
    except KeyboardInterrupt:
        return True
    return False


def test_a_swallowed_signal_is_raised_again_at_the_next_check():
    with interrupts.handled():
        interrupts.check()   # nothing came
        assert _swallowed(signal.SIGINT)
        with pytest.raises(KeyboardInterrupt):
            interrupts.check()
        interrupts.check()   # raised once
        assert _swallowed(signal.SIGTERM)
        interrupts.acknowledge()   # handled by whoever caught it
        interrupts.check()


def test_a_signal_while_a_file_is_written_is_raised_when_it_is_complete():
    finished = []
    with interrupts.handled():
        with pytest.raises(KeyboardInterrupt):
            with interrupts.deferred():
                os.kill(os.getpid(), signal.SIGTERM)
                time.sleep(0.05)
                finished.append(True)
        interrupts.check()   # raised once
    assert finished == [True]


def test_handlers_are_restored_and_an_ignored_sigint_stays_ignored():
    before = signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT)
    assert before[1] is signal.default_int_handler
    with interrupts.handled():
        assert signal.getsignal(signal.SIGTERM) is not before[0]
    assert (signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT)) == before
    signal.signal(signal.SIGINT, signal.SIG_IGN)   # a background job's
    try:
        with interrupts.handled():
            assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, before[1])


def test_a_sweep_stops_after_the_point_where_a_ctrl_c_was_swallowed(tmp_path):
    def progress(done, total):
        if done == 2:
            assert _swallowed()

    out = tmp_path / "tiny.nc"
    with interrupts.handled():
        with pytest.raises(SweepInterrupted, match=r"interrupted: 2 of 4 points are saved"):
            run_study(Study.model_validate(TINY), out, workers=1, progress=progress, log=None)
    assert done_count(out) == 2


def test_a_ctrl_c_while_a_sweep_point_is_written_stops_the_sweep_once_the_point_is_saved(tmp_path, monkeypatch):
    from blademodel.sweep import runner
    real = runner.storage.write_point

    def write(path, index, result):
        if index == 1:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)
        real(path, index, result)

    monkeypatch.setattr(runner.storage, "write_point", write)
    out = tmp_path / "tiny.nc"
    with interrupts.handled():
        with pytest.raises(SweepInterrupted, match=r"interrupted: 2 of 4 points are saved"):
            run_study(Study.model_validate(TINY), out, workers=1, progress=None, log=None)
    assert done_count(out) == 2
