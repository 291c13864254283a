"""Atomic file output: a reader never sees a half-written file, a crash leaves the old one.

The temporary file beside the target is named ``.<target>.<pid>.<random>.part`` (a long target
name shortened to its start and a hash, so the part name stays within 255 bytes): a process
killed with SIGKILL cannot remove it, so a process's first write into a folder removes every
part file there whose writer process no longer exists. Once per folder and process, not per
write: a sweep writes ~3 500 files into folders of up to a thousand, and the scan of the
folder at every write was half of an atomic write's CPU.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import secrets
from collections.abc import Iterator
from pathlib import Path

from spindlebench.core.paths import refuse_shipped


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; move it into place only if the block succeeds.

    Use it for writers that want a path (``DataFrame.to_csv``, ``savefig``, zip files).
    """
    with atomic_file(target) as part:
        part.close()  # the writer opens the path itself
        yield part.path


class PartFile:
    """The part file of an ``atomic_file`` block: its ``path``, open for ``write``."""

    def __init__(self, path: Path, handle: int) -> None:
        self.path = path
        self._handle: int | None = handle

    def write(self, data: bytes) -> None:
        """Write all of ``data`` (a bytes-like object) at the file's current end."""
        if self._handle is None:
            raise ValueError(f"{self.path}: closed")
        view = memoryview(data).cast("B")
        while view:
            view = view[os.write(self._handle, view):]

    def close(self) -> None:
        if self._handle is not None:
            handle, self._handle = self._handle, None
            os.close(handle)


@contextlib.contextmanager
def atomic_file(target: str | os.PathLike[str]) -> Iterator[PartFile]:
    """Yield the part file beside ``target``, open for writing; close it and move it into
    place only if the block succeeds.

    Why a handle and not only a path: the part file is made (``O_EXCL``) open already, and a
    writer that has its bytes in memory (a sweep's ~3 500 recordings, sidecars, result tables
    and manifests) wrote them by opening the same file again by path."""
    target = Path(target)
    refuse_shipped(target)  # never a shipped file, unless --overwrite-shipped says so
    _sweep_once(target.parent)
    tmp: Path | None = None
    part: PartFile | None = None
    try:
        # named before it is made, so a signal at any point (Ctrl-C right after the file was
        # made left it behind) finds ``tmp`` naming the file to remove
        while True:
            tmp = target.with_name(f".{_part_stem(target.name)}.{os.getpid()}."
                                   f"{secrets.token_hex(4)}.part")
            handle = _create(tmp, target.parent)
            if handle is not None:
                part = PartFile(tmp, handle)
                break
        yield part
        part.close()
        os.replace(tmp, target)
        tmp = None  # moved: nothing left to remove
    except OSError as exc:
        if exc.filename is None and exc.errno:  # the disk refused a write (full, quota, size)
            exc.filename = str(target)  # say which file: "No space left on device" alone
        raise
    finally:
        if part is not None:
            part.close()
        elif tmp is not None:  # a signal between making the file and holding its handle
            _close_handles_of(tmp)
        if tmp is not None:
            tmp.unlink(missing_ok=True)


def _close_handles_of(part: Path) -> None:
    """Close this process's handles of file ``part``: those a signal left open (it lands
    at the first bytecode after ``os.open`` returned, before the handle has a name). Read
    from ``/proc/self/fd`` (Linux; elsewhere such a handle stays open until the process
    ends). Only on that path, so a write pays nothing for it."""
    fds = "/proc/self/fd"
    if not os.path.isdir(fds):
        return
    try:
        wanted = os.path.realpath(part)
    except OSError:
        return
    for name in os.listdir(fds):
        with contextlib.suppress(OSError, ValueError):
            if os.readlink(os.path.join(fds, name)) == wanted:
                os.close(int(name))


def _create(part: Path, folder: Path) -> int | None:
    """Make the empty file ``part`` with the mode a plain ``open()`` gives (0666 less the
    umask) and return its handle, open for writing; None if the name is taken. Its folder is
    made again if it went away since this process first wrote there."""
    try:
        try:
            return os.open(part, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o666)
        except FileNotFoundError:
            folder.mkdir(parents=True, exist_ok=True)
            return os.open(part, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o666)
    except FileExistsError:
        return None


def _sweep_once(folder: Path) -> None:
    """Make ``folder`` and remove the stale part files in it, at this process's first write
    there."""
    key = os.path.abspath(folder)
    if key not in _swept:
        folder.mkdir(parents=True, exist_ok=True)
        remove_stale_parts_in(folder)
        _swept.add(key)


#: The folders this process has swept of stale part files (``remove_stale_parts_in``).
_swept: set[str] = set()


#: Longest target name kept whole in a part file's name: a name near the file system's 255
#: bytes (a 245-character --json) plus the pid and random suffix was refused as too long.
_PART_NAME_CHARS = 100


def _part_stem(name: str) -> str:
    """The target's name as its part files carry it: whole when short, else its start and a
    hash of the whole (so two long names sharing a start do not share part files)."""
    if len(name.encode("utf-8")) <= _PART_NAME_CHARS:
        return name
    digest = hashlib.sha256(name.encode("utf-8")).hexdigest()[:12]
    return f"{name.encode('utf-8')[:40].decode('utf-8', 'ignore')}~{digest}"


def write_text(target: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` to ``target`` atomically (UTF-8)."""
    write_bytes(target, text.encode("utf-8"))


def write_bytes(target: str | os.PathLike[str], data: bytes) -> None:
    """Write ``data`` to ``target`` atomically."""
    with atomic_file(target) as part:
        part.write(data)


def _process_exists(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's live process
        return True
    return True


def remove_stale_parts_in(folder: str | os.PathLike[str]) -> list[Path]:
    """Remove the part files in ``folder`` left by writers that were killed; return them.

    A part file is ``.<stem>.<pid>.<random>.part``; one of a live process (a concurrent
    writer) is left alone."""
    with os.scandir(folder) as entries:
        names = [entry.name for entry in entries if entry.name.startswith(".")
                 and entry.name.endswith(".part") and entry.is_file(follow_symlinks=False)]
    removed = []
    alive: dict[int, bool] = {}
    for name in names:
        fields = name[1:-len(".part")].rsplit(".", 2)  # stem (may hold dots), pid, random
        if len(fields) < 3 or not fields[1].isdigit():
            continue
        pid = int(fields[1])
        if pid not in alive:
            alive[pid] = _process_exists(pid)
        if not alive[pid]:
            part = Path(folder) / name
            with contextlib.suppress(FileNotFoundError):
                part.unlink()
                removed.append(part)
    return removed
