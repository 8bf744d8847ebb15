"""Output paths of the commands, checked before any computing.

A command that writes a file checks ``--out`` up front: the name must carry the
file's suffix (NumPy's ``savez`` would append ``.npz`` to ``x.txt`` and save
``x.txt.npz``), the folder must exist and accept a new file. Each refusal is a
``ValueError`` naming the option, the path and the reason, so the command line
exits with code 2 before a run starts instead of failing after it.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def check_writable_folder(folder: Path, label: str) -> None:
    """Refuse a missing folder, a file in its place, or one where no file can be created.

    Parameters
    ----------
    folder : Path
    label : str
        How the path is named in messages (``"--out x/r.npz"``).

    Raises
    ------
    ValueError
    """
    if not folder.exists():
        raise ValueError(f"{label}: folder {str(folder)!r} does not exist; create it first")
    if not folder.is_dir():
        raise ValueError(f"{label}: {str(folder)!r} is not a folder")
    try:  # os.access says yes to root on a read-only file system; creating a file tells the truth
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".blademodel-write-check-"):
            pass
    except OSError as e:
        raise ValueError(f"{label}: cannot write in folder {str(folder)!r}: {e.strerror or e}") from None


def check_output_file(path: str | os.PathLike, suffix: str, *, option: str = "--out", what: str = "file",
                      make_folders: bool = False) -> Path:
    """Check an output file name before anything is computed.

    Parameters
    ----------
    path : str or path-like
        The file to write.
    suffix : str
        Its required suffix, e.g. ``".npz"`` (compared case-insensitively).
    option : str
        The option that gave the path, for messages.
    what : str
        What the file holds, for messages (``"NumPy .npz archive"``).
    make_folders : bool
        The command creates missing folders: check the nearest existing one instead.

    Returns
    -------
    Path

    Raises
    ------
    ValueError
        If the suffix differs, the path is a folder, its folder is missing (unless
        ``make_folders``) or not writable, or an existing file there cannot be replaced.
    """
    p = Path(path)
    label = f"{option} {str(path)!r}"
    if p.suffix.lower() != suffix.lower():
        raise ValueError(f"{label}: the result is a {what}; give a file name ending in {suffix}")
    if p.is_dir():
        raise ValueError(f"{label}: is a folder; give a file name ending in {suffix}")
    folder = p.parent
    if make_folders:
        while not folder.exists() and folder != folder.parent:
            folder = folder.parent
    check_writable_folder(folder, label)
    if p.exists() and not os.access(p, os.W_OK):
        raise ValueError(f"{label}: the existing file cannot be replaced (no write permission)")
    return p
