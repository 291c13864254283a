"""What a command may read and where it may write: one home for the checks on paths.

Inputs: a FIFO or a device named as a recording, scenario, study, map or config blocked
forever (a FIFO without a writer) or read without end (``/dev/zero`` filled the memory); an
input must be a regular file, of a size its reader can hold. Outputs: an output that names
one of the command's own inputs (``evaluate --json train.csv``) replaced the input; one
that names a device, a FIFO or ``/`` is not a file to write. Each is one line naming the
path and what to do.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Iterable
from pathlib import Path

from spindlebench.core.errors import SpindlebenchError

#: The largest text file (TOML, JSON, a measured-ambient CSV) a reader takes in at once:
#: far above any real one (the shipped files are kilobytes), far below the memory.
MAX_TEXT_BYTES = 64 * 1024 * 1024
#: The largest recording CSV: read whole (and parsed to float64) it needs a few times its
#: size in memory; a 4 GB sparse file was a traceback. Real ones here are under 100 MB.
MAX_RECORDING_BYTES = 2 * 1024**3


def special_kind(mode: int) -> str | None:
    """What a non-regular, non-directory file is (None for a regular file or a folder)."""
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode):
        return "a character device"
    if stat.S_ISBLK(mode):
        return "a block device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return None


def _stat(path: Path) -> tuple[os.stat_result | None, str | None]:
    """The path's status and its special kind (both None for a path that does not exist:
    its reader or writer says so in its own words)."""
    try:
        info = os.stat(path)
    except OSError:
        return None, None
    return info, special_kind(info.st_mode)


def check_input(path: str | Path, what: str = "file",
                max_bytes: int | None = MAX_TEXT_BYTES) -> Path:
    """``path`` as an input the reader can take: a regular file (one line otherwise, before
    anything opens it: opening a FIFO blocks), not larger than ``max_bytes``. A missing
    path or a folder is left to the reader's own message."""
    path = Path(path)
    info, kind = _stat(path)
    if info is None:
        return path
    if kind is not None:
        raise SpindlebenchError(f"{path}: is {kind}, not a regular file; give the {what} as "
                                "a file (reading this could block or never end)")
    if max_bytes is not None and stat.S_ISREG(info.st_mode) and info.st_size > max_bytes:
        raise SpindlebenchError(f"{path}: {info.st_size / 2**20:.0f} MB is too large for a "
                                f"{what} (at most {max_bytes // 2**20} MB)")
    return path


def _same(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def check_output(path: str | Path, flag: str, inputs: Iterable[str | Path] = (),
                 folder: bool = False) -> Path:
    """``path`` as a place to write: not one of ``inputs`` (it would replace it), not a
    device, FIFO or socket, not the root folder, and a folder (``folder``) or not one."""
    path = Path(path)
    if path.resolve() == Path(path.resolve().anchor):
        raise SpindlebenchError(f"{flag} {path}: the root folder; give a folder of its own")
    for source in inputs:
        source = Path(source)
        if _same(path, source) or (not path.exists() and path.resolve() == source.resolve()):
            raise SpindlebenchError(f"{flag} {path}: is one of this command's inputs "
                                    f"({source}); writing it would replace the input: give "
                                    "another path")
    info, kind = _stat(path)
    if info is None:
        return path
    if kind is not None:
        raise SpindlebenchError(f"{flag} {path}: is {kind}, not a file to write; give a "
                                "file path")
    if not folder and stat.S_ISDIR(info.st_mode):
        raise SpindlebenchError(f"{flag} {path}: is a directory; give a file name")
    return path
