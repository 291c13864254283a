"""Where the package finds its data: the FMU, the Modelica source and the shipped scenarios.

In a checkout (an editable install) they are the repository's own ``fmus/``, ``models/`` and
``scenarios/``, so a rebuilt FMU or an edited scenario is used at once. An installed wheel
(``pip install .``) carries copies of them in ``spindlebench/_data`` (see ``setup.py``), so the
package also works outside the checkout. Every module asks here; none counts ``parents[n]``.
"""

from __future__ import annotations

import contextlib
import contextvars
import functools
import os
import stat
from collections.abc import Iterator
from pathlib import Path

from spindlebench.core.names import FMU_NAME

#: This package (``spindlebench/``; this module is ``spindlebench/core/paths.py``).
_PACKAGE = Path(__file__).resolve().parents[1]
#: The checkout holding this package (``pipeline/spindlebench``), or None when installed.
_CHECKOUT = _PACKAGE.parents[1]


def _is_checkout(folder: Path) -> bool:
    return (folder / "pyproject.toml").is_file() and (folder / "pipeline" / "spindlebench").is_dir()


#: Root of the package data: the repository in a checkout, ``spindlebench/_data`` when installed.
DATA_ROOT: Path = _CHECKOUT if _is_checkout(_CHECKOUT) else _PACKAGE / "_data"
#: The repository root, or None when the package is installed from a wheel.
REPO_ROOT: Path | None = DATA_ROOT if DATA_ROOT == _CHECKOUT else None


#: The project's default FMU, built from models/ by ``spindlebench build``.
DEFAULT_FMU: Path = DATA_ROOT / "fmus" / f"{FMU_NAME}.fmu"
#: The Modelica source folder the FMU is built from.
MODELS_DIR: Path = DATA_ROOT / "models"
#: The shipped scenarios (paper experiments, examples, studies, climates).
SCENARIOS_DIR: Path = DATA_ROOT / "scenarios"
#: Shipped climate tables (``<name>.toml``).
SEASONS_DIR: Path = SCENARIOS_DIR / "seasons"
#: The benchmark suites (``<suite>.toml``, ``spindlebench benchmark``).
BENCHMARKS_DIR: Path = DATA_ROOT / "benchmarks"


#: Overrides where the package keeps what it computes once and reuses (``user_cache_dir``).
CACHE_ENV = "SPINDLEBENCH_CACHE"


def user_cache_dir() -> Path:
    """The per-user folder for reusable computed data (soak states, translated models, the
    fingerprint reference, the course's default working folders): ``$SPINDLEBENCH_CACHE``, else
    ``$XDG_CACHE_HOME/spindlebench``, else ``~/.cache/spindlebench``.

    Never the current folder: a command writes there only what it is told to write (its
    ``-o``/``--out``), so running one inside a checkout or a student's folder leaves nothing
    behind that nobody asked for."""
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "spindlebench"


def user_cache_folder(name: str, env: str) -> Path:
    """One cache's folder: ``$env`` where set, else ``name`` in ``user_cache_dir()``."""
    return Path(os.environ.get(env) or user_cache_dir() / name)


#: The folders whose existing files are shipped with the package (with the committed FMU): a
#: command writing there would replace the default machine, a climate or the model.
SHIPPED_DIRS: tuple[Path, ...] = (MODELS_DIR, SCENARIOS_DIR)
#: The flag that lets one command replace a shipped file.
OVERWRITE_SHIPPED_FLAG = "--overwrite-shipped"
_shipped_allowed: contextvars.ContextVar[frozenset[Path] | bool] = contextvars.ContextVar(
    "shipped_allowed", default=frozenset())


def shipped(path: str | os.PathLike[str]) -> bool:
    """Whether writing ``path`` would change what the package ships: an existing file in
    ``models/`` or ``scenarios/``, the committed FMU, or anything inside the package's source
    tree (links resolved, so ``./x/../scenarios/...`` or a link to it counts too)."""
    resolved = _resolved(Path(path))
    fmu, package, folders = _shipped_places()
    if _within(resolved, package) or resolved == fmu:
        return True
    return any(_within(resolved, folder) for folder in folders) \
        and os.path.isfile(resolved) and _committed(Path(resolved))


def _within(resolved: str, folder: str) -> bool:
    """``Path(resolved).is_relative_to(folder)`` for two resolved paths, as text (pathlib
    parsed both at every call, three calls per atomic write)."""
    return resolved == folder or resolved.startswith(folder.rstrip("/") + "/")


def _resolved(path: Path) -> str:
    """``str(path.resolve())``, its folder resolved once per process (an existing folder is
    taken to stay where it is while the process runs) and the file itself looked at each
    time (a link is resolved in full). Why: a sweep checks ~6 000 outputs in a few hundred
    folders, and resolving each path cost a ``stat`` per part of it, ~30 µs a write."""
    name = path.name
    if name in ("", ".."):
        return str(path.resolve())
    try:
        if stat.S_ISLNK(os.lstat(path).st_mode):
            return str(path.resolve())
    except OSError:
        pass  # not there (or not reachable): resolve() takes it as it is, so does this
    folder = os.path.join(os.getcwd(), os.fspath(path.parent))
    place = _resolved_folders.get(folder)
    if place is None:
        place = str(Path(folder).resolve())
        if os.path.isdir(folder):
            _resolved_folders[folder] = place
    return os.path.join(place, name)


#: Existing folders (absolute, as named) and where they resolve to (``_resolved``).
_resolved_folders: dict[str, str] = {}


@functools.cache
def _shipped_places() -> tuple[str, str, tuple[str, ...]]:
    """The committed FMU, the package and ``SHIPPED_DIRS``, links resolved, as text: once, as
    they do not move while a process runs (resolving them at every atomic write was ~40 µs
    of its ~90 µs check; a sweep makes ~6 000)."""
    return (str(DEFAULT_FMU.resolve()), str(_PACKAGE),
            tuple(str(folder.resolve()) for folder in SHIPPED_DIRS))


def _committed(resolved: Path) -> bool:
    """Whether a file of the checkout is one the repository ships (tracked by git), so a
    user's own ``scenarios/machines/mine.toml`` can be calibrated again; without git (or
    outside a checkout) every existing file there counts as shipped."""
    if REPO_ROOT is None or not (REPO_ROOT / ".git").exists():
        return True
    import subprocess

    try:
        found = subprocess.run(["git", "-C", str(REPO_ROOT), "ls-files", "--error-unmatch",
                                "--", str(resolved.relative_to(REPO_ROOT.resolve()))],
                               capture_output=True, timeout=10, check=False)
    except (OSError, ValueError, subprocess.TimeoutExpired):
        return True
    return found.returncode == 0


@contextlib.contextmanager
def allow_shipped(*paths: str | os.PathLike[str]) -> Iterator[None]:
    """Within the block, writing these shipped paths (none given: every one) is allowed:
    ``--overwrite-shipped``, or ``build`` rebuilding the committed FMU from its own sources."""
    allowed: frozenset[Path] | bool = (
        True if not paths else frozenset(Path(p).resolve() for p in paths))
    token = _shipped_allowed.set(allowed)
    try:
        yield
    finally:
        _shipped_allowed.reset(token)


def refuse_shipped(path: str | os.PathLike[str]) -> None:
    """Refuse, in one line naming the flag, an output that would replace a shipped file."""
    allowed = _shipped_allowed.get()
    if allowed is True or not shipped(path):
        return
    if Path(path).resolve() in allowed:  # type: ignore[operator]
        return
    from spindlebench.core.errors import SpindlebenchError

    raise SpindlebenchError(f"{path}: is shipped with spindlebench (the committed FMU, models/, "
                            f"scenarios/ or the package source); write elsewhere, or give "
                            f"{OVERWRITE_SHIPPED_FLAG} to replace it")


def file_kind(path: str | os.PathLike[str]) -> str:
    """What ``path`` is, for a message: 'a file', 'a folder', or the special kind
    ``core.files.special_kind`` names ('a FIFO (named pipe)', 'a socket', ...)."""
    from spindlebench.core.files import special_kind

    mode = Path(path).stat().st_mode
    if stat.S_ISREG(mode):
        return "a file"
    if stat.S_ISDIR(mode):
        return "a folder"
    return special_kind(mode) or "not a regular file"


def shared_recordings_dir() -> Path:
    """Real recordings: ``../shared/recordings`` beside the checkout (never copied into it);
    installed, beside the current folder."""
    base = REPO_ROOT if REPO_ROOT is not None else Path.cwd()
    return base.parent / "shared" / "recordings"


def shown(path: Path) -> str:
    """A path as a user would type it: relative to the current folder when inside it
    (``models``, ``fmus/SpindleBench.fmu`` in the checkout), else absolute."""
    try:
        return os.path.relpath(path) if path.resolve().is_relative_to(Path.cwd()) else str(path)
    except ValueError:
        return str(path)
