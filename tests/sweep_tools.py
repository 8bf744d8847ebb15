"""Helpers of the sweep reliability tests: tiny studies, CLI runs, raw file contents, process tracking.

Every CLI sweep a test starts carries a unique ``BLADEMODEL_TEST_TAG`` in its
environment, which its pool workers inherit, so the processes a test started
(and any it left behind) are found through ``/proc/<pid>/environ`` even after
they were re-parented.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path

import netCDF4
import numpy as np
import yaml

#: A tiny study: 4 points of a few milliseconds each.
TINY = {"name": "tiny", "base": {"model": "blade_pair", "friction": "bilinear"},
        "sweep": {"gamma": {"values": [3.0, 5.0, 7.0, 9.0]}},
        "run": {"transient": 10, "periods": 4, "steps_per_period": 200}}
#: The same with points of about half a second, so kills land mid-sweep.
SLOW = {**TINY, "name": "slow", "sweep": {"gamma": {"values": [3.0, 4.0, 5.0, 6.0, 7.0, 8.0]}},
        "run": {"transient": 1500, "periods": 4, "steps_per_period": 1000}}


def write_study(folder: Path, data: dict, name: str = "study.yaml") -> Path:
    path = Path(folder) / name
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def cli_env(tag: str | None = None, **extra) -> dict:
    env = dict(os.environ, MPLBACKEND="Agg", BLADEMODEL_TEST_TAG=tag or uuid.uuid4().hex, **extra)
    env.pop("PYTHONWARNINGS", None)
    return env


def cli(*args, cwd=None, env=None, timeout=120) -> subprocess.CompletedProcess:
    """Run ``blademodel *args`` to its end."""
    return subprocess.run([sys.executable, "-m", "blademodel", *map(str, args)], cwd=cwd, env=env or cli_env(),
                          capture_output=True, text=True, timeout=timeout)


def start(*args, cwd=None, tag: str, **kw) -> subprocess.Popen:
    """Start ``blademodel *args`` in its own session (so a Ctrl-C can go to its process group)."""
    return subprocess.Popen([sys.executable, "-m", "blademodel", *map(str, args)], cwd=cwd, env=cli_env(tag),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                            preexec_fn=_default_sigint, **kw)


def _default_sigint():
    # As from a terminal: a shell starts background jobs (``pytest ... &``, ``nohup``) with SIGINT
    # ignored, children inherit that, and Python then installs no KeyboardInterrupt handler.
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def tagged(tag: str) -> list[int]:
    """Live processes (not zombies) whose environment holds ``BLADEMODEL_TEST_TAG=tag``."""
    needle = f"BLADEMODEL_TEST_TAG={tag}".encode()
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            if needle not in Path(f"/proc/{entry}/environ").read_bytes().split(b"\0"):
                continue
            state = Path(f"/proc/{entry}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if state not in ("Z", "X"):
            found.append(int(entry))
    return found


def wait_until(condition, timeout: float, step: float = 0.02) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(step)
    return bool(condition())


def done_count(path: Path) -> int:
    """Points marked done in a result file being written (0 while it cannot be read)."""
    try:
        with netCDF4.Dataset(path) as ds:
            return int(np.sum(np.asarray(ds["done"][:]) != 0))
    except (OSError, RuntimeError, IndexError, KeyError):
        return 0


def raw_contents(path: Path) -> tuple[dict, dict]:
    """Every variable's stored bytes and every attribute: equal for bit-identical results."""
    with netCDF4.Dataset(path) as ds:
        ds.set_auto_maskandscale(False)
        ds.set_auto_chartostring(False)
        data = {n: np.asarray(v[:]).tobytes() for n, v in ds.variables.items()}
        attrs = {a: ds.getncattr(a) for a in ds.ncattrs()}
    return data, attrs


def kill_all(tag: str) -> None:
    """Clean-up: SIGKILL whatever a test left running."""
    for pid in tagged(tag):
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


def one_line(text: str) -> str:
    """The message of a command that must say one line and no traceback."""
    lines = [line for line in text.splitlines() if line.strip()]
    assert "Traceback" not in text, text
    assert len(lines) == 1, text
    return lines[0]
