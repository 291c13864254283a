"""Where the package finds its data: the FMU, the Modelica source and the shipped scenarios.

In a checkout (an editable install) they are the repository's own ``fmus/``, ``models/`` and
``scenarios/``, so a rebuilt FMU or an edited scenario is used at once. An installed wheel
(``pip install .``) carries copies of them in ``spindlebench/_data`` (see ``setup.py``), so the
package also works outside the checkout. Every module asks here; none counts ``parents[n]``.
"""

from __future__ import annotations

import os
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
    """The per-user folder for reusable computed data (soak states, the fingerprint
    reference, the course's default working folders): ``$SPINDLEBENCH_CACHE``, else
    ``$XDG_CACHE_HOME/spindlebench``, else ``~/.cache/spindlebench``.

    Never the current folder: a command writes there only what it is told to write (its
    ``-o``/``--out``), so running one inside a checkout or a student's folder leaves nothing
    behind that nobody asked for."""
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "spindlebench"


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
