"""Atomic file output: a reader never sees a half-written file, a crash leaves the old one.

The temporary file beside the target is named ``.<target>.<pid>.<random>.part`` (a long target
name shortened to its start and a hash, so the part name stays within 255 bytes): a process
killed with SIGKILL cannot remove it, so the next write of the same target removes every
part file of that target whose writer process no longer exists.
"""

from __future__ import annotations

import contextlib
import glob
import hashlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from spindlebench.core import interrupts
from spindlebench.core.paths import refuse_shipped


def _current_umask() -> int:
    """The process umask (read by setting and restoring it; there is no getter)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; move it into place only if the block succeeds.

    Use it for writers that want a path (``DataFrame.to_csv``, ``savefig``, zip files).
    """
    target = Path(target)
    refuse_shipped(target)  # never a shipped file, unless --overwrite-shipped says so
    target.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_parts(target)
    tmp: Path | None = None
    try:
        # a signal between making the part file and knowing its name left it behind (seen
        # with Ctrl-C during a study's manifest write): made with signals deferred, so once
        # one raises (at the end of this block at the latest) ``tmp`` names the file to remove
        with interrupts.deferred():
            fd, tmp_name = tempfile.mkstemp(prefix=f".{_part_stem(target.name)}.{os.getpid()}.",
                                            suffix=".part", dir=target.parent)
            tmp = Path(tmp_name)
            os.close(fd)
        # mkstemp makes the file private (0600); give it the mode a plain open() would.
        os.chmod(tmp, 0o666 & ~_current_umask())
        yield tmp
        os.replace(tmp, target)
    except OSError as exc:
        if exc.filename is None and exc.errno:  # the disk refused a write (full, quota, size)
            exc.filename = str(target)  # say which file: "No space left on device" alone
        raise
    finally:
        if tmp is not None and tmp.exists():
            tmp.unlink()


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
    with atomic_path(target) as tmp:
        tmp.write_text(text, encoding="utf-8")


def write_bytes(target: str | os.PathLike[str], data: bytes) -> None:
    """Write ``data`` to ``target`` atomically."""
    with atomic_path(target) as tmp:
        tmp.write_bytes(data)


def _process_exists(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's live process
        return True
    return True


def remove_stale_parts(target: str | os.PathLike[str]) -> list[Path]:
    """Remove the part files of ``target`` left by writers that were killed; return them.

    A part file of a live process (a concurrent writer) is left alone.
    """
    target = Path(target)
    removed = []
    stem = _part_stem(target.name)
    for part in target.parent.glob(f".{glob.escape(stem)}.*.part"):
        pid_text = part.name[len(stem) + 2:].split(".", 1)[0]
        if pid_text.isdigit() and not _process_exists(int(pid_text)):
            with contextlib.suppress(FileNotFoundError):
                part.unlink()
                removed.append(part)
    return removed

