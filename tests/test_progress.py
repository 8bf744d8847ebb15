"""Progress reports: a redrawn bar on a terminal, timed log lines otherwise."""

import io

import pytest

from blademodel.progress import Progress, duration


class Clock:
    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


class Terminal(io.StringIO):
    def isatty(self):
        return True


@pytest.mark.parametrize("seconds, text", [(0.4, "0 s"), (59.4, "59 s"), (65, "1 min 05 s"),
                                           (3599, "59 min 59 s"), (7620, "2 h 07 min")])
def test_duration(seconds, text):
    assert duration(seconds) == text


def test_log_lines_are_timed_and_a_short_run_is_silent():
    clock, out = Clock(), io.StringIO()
    p = Progress("points", label="fig06", stream=out, interval=30.0, clock=clock)
    for done in range(0, 11):   # 10 points, 1 s each: shorter than the interval
        p(done, 10)
        clock.t += 1.0
    assert out.getvalue() == ""

    clock, out = Clock(), io.StringIO()
    p = Progress("points", label="fig06", stream=out, interval=30.0, clock=clock)
    for done in range(0, 101):   # 100 points, 1 s each
        p(done, 100)
        clock.t += 1.0
    lines = out.getvalue().splitlines()
    # one line every 30 s (at 30, 60, 90 s) and the final one; no carriage returns
    assert len(lines) == 4 and "\r" not in out.getvalue()
    assert lines[0] == "fig06: 30/100 points (30 %), 30 s, about 1 min 10 s left"
    assert lines[-1] == "fig06: 100/100 points (100 %), 1 min 40 s"


def test_time_left_counts_only_the_work_of_this_run():
    """A resumed sweep starts at 50 of 100: its rate is measured from there."""
    clock, out = Clock(), Terminal()
    p = Progress("points", stream=out, clock=clock)
    p(50, 100)
    clock.t += 20.0
    p(60, 100)   # 10 points in 20 s -> 40 points left take 80 s
    assert out.getvalue().endswith("60/100 points (60 %), 20 s, about 1 min 20 s left\x1b[K")


def test_terminal_bar_redraws_one_line_and_ends_it():
    clock, out = Clock(), Terminal()
    p = Progress("periods", stream=out, clock=clock)
    for done in (0, 5, 10):
        p(done, 10)
    text = out.getvalue()
    assert text.count("\r") == 3 and text.count("\n") == 1 and text.endswith("\n")
    assert "[###############               ] 5/10 periods (50 %)" in text


def test_unknown_total_shows_the_note_and_interrupt_ends_the_line():
    clock, out = Clock(), Terminal()
    p = Progress("points", label="branch", stream=out, clock=clock)
    p(3, 0, "omega = 281.5")
    assert out.getvalue() == "\rbranch: 3 points, omega = 281.5, 0 s\x1b[K"
    p.interrupt()
    p.interrupt()   # only once
    assert out.getvalue().endswith("\x1b[K\n")


def test_a_sweep_not_on_a_terminal_logs_its_progress(tmp_path, monkeypatch, capsys):
    """Standard error captured (not a terminal): every point is logged with interval 0, one line each."""
    import blademodel.progress
    from blademodel.sweep import Study, run_study
    from sweep_tools import TINY

    monkeypatch.setattr(blademodel.progress, "LOG_INTERVAL", 0.0)
    run_study(Study.model_validate(TINY), tmp_path / "tiny.nc", workers=1, log=None)
    lines = capsys.readouterr().err.splitlines()
    assert [line.split(",")[0] for line in lines] == [f"tiny.nc: {k}/4 points ({25 * k} %)" for k in range(5)]
