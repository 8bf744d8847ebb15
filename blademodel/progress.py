"""Progress of long runs: a bar on a terminal, plain log lines otherwise.

A sweep, a long simulation or a continuation reports ``(done, total)`` after
every unit of work. On a terminal that redraws one line (bar, count, elapsed
time, time left); when standard error is a file or a pipe (a batch job, CI,
``nohup``), redrawing would fill the log with carriage returns, so a complete
line is written once every ``interval`` seconds, and at the end if any line was
written before (a short run stays silent).
"""

from __future__ import annotations

import os
import sys
import time
from typing import Callable, Optional, TextIO

#: Seconds between two progress lines when standard error is not a terminal
#: (``$BLADEMODEL_PROGRESS_SECONDS``, default 30).
LOG_INTERVAL = float(os.environ.get("BLADEMODEL_PROGRESS_SECONDS", 30.0))


def duration(seconds: float) -> str:
    """``'42 s'``, ``'3 min 05 s'`` or ``'2 h 07 min'``."""
    s = int(round(seconds))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s // 3600} h {s % 3600 // 60:02d} min"


class Progress:
    """A ``progress(done, total)`` callable that writes to ``stream`` (standard error by default).

    Parameters
    ----------
    unit : str
        What is counted (``"points"``, ``"periods"``).
    label : str, optional
        Put in front of every line (e.g. the study's name).
    stream : file, optional
        Default: ``sys.stderr`` at the time of each call.
    interval : float, optional
        Seconds between two lines when ``stream`` is not a terminal (default
        :data:`LOG_INTERVAL`).
    clock : callable
        Seconds, monotonic (injectable for tests).

    Notes
    -----
    The time left is extrapolated from the work done *in this run*: points
    reused from an earlier run (the first ``done`` reported) do not count.
    """

    def __init__(self, unit: str, label: str = "", stream: Optional[TextIO] = None,
                 interval: Optional[float] = None, clock: Callable[[], float] = time.monotonic):
        self.unit, self.label, self._stream = unit, label, stream
        self.interval = LOG_INTERVAL if interval is None else interval
        self.clock = clock
        self._start: Optional[float] = None
        self._first = 0
        self._last_line = 0.0
        self._logged = False
        self._open_line = False

    @property
    def stream(self) -> TextIO:
        return self._stream if self._stream is not None else sys.stderr

    def _text(self, done: int, total: int, now: float, note: str) -> str:
        elapsed = now - self._start
        text = f"{self.label}: " if self.label else ""
        text += f"{done}/{total} {self.unit} ({100 * done / total:.0f} %)" if total else f"{done} {self.unit}"
        text += (f", {note}" if note else "") + f", {duration(elapsed)}"
        if total and 0 < done - self._first and done < total:
            text += f", about {duration(elapsed * (total - done) / (done - self._first))} left"
        return text

    def __call__(self, done: int, total: int = 0, note: str = "") -> None:
        """Report ``done`` of ``total`` units (``total = 0``: not known in advance; ``note``: shown after the count)."""
        now = self.clock()
        if self._start is None:
            self._start, self._first, self._last_line = now, done, now
        stream = self.stream
        complete = bool(total) and done >= total
        if stream.isatty():
            text = self._text(done, total, now, note)
            if total:
                text = f"[{'#' * int(30 * done / total):<30}] {text}"
            print(f"\r{text}\x1b[K", end="\n" if complete else "", file=stream, flush=True)
            self._open_line = not complete
        elif (complete and self._logged) or now - self._last_line >= self.interval:
            print(self._text(done, total, now, note), file=stream, flush=True)
            self._last_line, self._logged = now, True

    def interrupt(self) -> None:
        """End a half-drawn terminal line (before an error message is printed)."""
        if self._open_line:
            print(file=self.stream)
            self._open_line = False
