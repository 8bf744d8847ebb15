"""One writer per result file: an exclusive lock next to it, naming its owner.

``out/x.nc`` is locked through ``out/x.nc.lock``. On POSIX systems the lock is
an ``fcntl.flock`` on that file, which the operating system releases when the
owner exits in any way (even ``SIGKILL``), so a lock is never left stale; the
file holds the owner's process id, host, start time and command line, which a
refused second sweep reports. Elsewhere the lock file is created with
``O_EXCL`` and removed on release; a lock left by a killed process must then be
removed by hand, as the message says.
"""

from __future__ import annotations

import json
import os
import socket
import sys
import time
from pathlib import Path

from .errors import ResultLockedError

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX
    fcntl = None


def lock_path(path: str | Path) -> Path:
    """The lock file of the result file ``path``."""
    path = Path(path)
    return path.with_name(path.name + ".lock")


def _owner() -> dict:
    return {"pid": os.getpid(), "host": socket.gethostname(),
            "started": time.strftime("%Y-%m-%d %H:%M:%S %Z"), "command": " ".join(sys.argv)}


def _read_owner(fd: int) -> dict:
    try:
        os.lseek(fd, 0, os.SEEK_SET)
        return json.loads(os.read(fd, 65536).decode() or "{}")
    except (OSError, ValueError):
        return {}


def _refuse(path: Path, owner: dict) -> ResultLockedError:
    who = f"process {owner.get('pid', '?')} on {owner.get('host', '?')}"
    if owner.get("started"):
        who += f", since {owner['started']}"
    if owner.get("command"):
        who += f": {owner['command']}"
    hint = "wait for it to finish or stop it"
    if fcntl is None:
        hint += f"; if no such process runs, remove {lock_path(path)}"
    return ResultLockedError(f"{path} is being written by another sweep ({who}); {hint}",
                             path=str(path), owner=owner)


class ResultLock:
    """Exclusive lock of a result file, as a context manager.

    Parameters
    ----------
    path : path-like
        The result file (it need not exist yet).

    Raises
    ------
    ResultLockedError
        On entry, if another process holds the lock; the message names the file
        and that process.

    Examples
    --------
    >>> with ResultLock("out/x.nc"):          # doctest: +SKIP
    ...     write_the_file()
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self.lock = lock_path(path)
        self._fd: int | None = None

    def __enter__(self) -> "ResultLock":
        self.acquire()
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    def acquire(self) -> None:
        """Take the lock or raise :class:`ResultLockedError`."""
        self.lock.parent.mkdir(parents=True, exist_ok=True)
        if fcntl is None:  # pragma: no cover - not POSIX
            self._acquire_exclusive_create()
            return
        while True:
            fd = os.open(self.lock, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                owner = _read_owner(fd)
                os.close(fd)
                raise _refuse(self.path, owner) from None
            # The holder before us may have removed the file after we opened it:
            # then our lock is on a file nobody else sees; take the one at the path.
            try:
                same = os.stat(self.lock).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        os.ftruncate(fd, 0)
        os.write(fd, json.dumps(_owner()).encode())
        self._fd = fd

    def _acquire_exclusive_create(self) -> None:  # pragma: no cover - not POSIX
        try:
            fd = os.open(self.lock, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            try:
                owner = json.loads(self.lock.read_text() or "{}")
            except (OSError, ValueError):
                owner = {}
            raise _refuse(self.path, owner) from None
        os.write(fd, json.dumps(_owner()).encode())
        self._fd = fd

    def release(self) -> None:
        """Remove the lock file and release the lock (nothing if not held)."""
        if self._fd is None:
            return
        try:
            self.lock.unlink()
        except FileNotFoundError:
            pass
        os.close(self._fd)   # closing releases the flock
        self._fd = None
