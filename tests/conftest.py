"""Shared test set-up: the repository's paths and fixtures more than one test module uses.

Test modules import the paths (``from conftest import REPO``); fixtures are found by pytest.
"""

from __future__ import annotations

from pathlib import Path

import pytest

#: The repository root (the folder holding ``tests/``).
REPO = Path(__file__).resolve().parents[1]
MODELS = REPO / "models"
FMU = REPO / "fmus" / "SpindleBench.fmu"
SCENARIOS = REPO / "scenarios"
#: The real recordings, outside the repository (never copied in).
SHARED_RECORDINGS = REPO.parent / "shared" / "recordings"
REAL_RECORDING = SHARED_RECORDINGS / "caiviac-fl-thermal" / "data.csv"
#: A 10-minute constant-speed scenario: the smallest real simulation, for tests that feed it
#: bad variations or interrupt it.
QUICK = """\
duration_s = 600
step_s = 10.0
sample_interval_s = 60
seed = 2

[speed]
kind = "constant"
rpm = 3000

[feed]
kind = "with_spindle"
x_mm_per_min = 1500
y_mm_per_min = 1500

[ambient]
kind = "constant"
temperature_C = 18.0
"""


@pytest.fixture(scope="session")
def repo() -> Path:
    """The repository root."""
    return REPO


#: The slowest modules, longest first: each builds the FMU from the Modelica source (gcc on
#: 1.5 MB of generated C) or executes the course's notebooks. They are collected first so
#: that under ``make test`` (pytest-xdist, ``--dist loadfile --no-loadscope-reorder``) they
#: start at once on different workers instead of being the last, lone, tail of the run.
SLOW_FIRST = ("test_fmu_build.py", "test_install.py", "test_notebooks.py")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Run the modules of ``SLOW_FIRST`` first (in that order), every other in its order."""
    def rank(item: pytest.Item) -> int:
        name = item.path.name
        return SLOW_FIRST.index(name) if name in SLOW_FIRST else len(SLOW_FIRST)

    items.sort(key=rank)  # stable: the order inside each module is kept


#: What a test run may add to the checkout: caches of Python and of the tools themselves.
_ALLOWED_LEFTOVERS = ("__pycache__", ".pytest_cache", ".ruff_cache", ".venv", ".egg-info",
                      "build/")
_checkout_before: set[str] | None = None


def _untracked() -> set[str] | None:
    """The checkout's untracked and ignored entries (``git status``), or None without git."""
    import subprocess

    try:
        done = subprocess.run(["git", "-C", str(REPO), "status", "--porcelain", "--ignored"],
                              capture_output=True, text=True, timeout=60, check=True)
    except (OSError, subprocess.SubprocessError):
        return None
    return {line[3:] for line in done.stdout.splitlines()
            if line[:2] in ("??", "!!") and not any(a in line for a in _ALLOWED_LEFTOVERS)}


def pytest_sessionstart(session: pytest.Session) -> None:
    global _checkout_before
    if not hasattr(session.config, "workerinput"):  # the controller, not an xdist worker
        _checkout_before = _untracked()


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """Fail the run if it left files in the checkout (tests write under ``tmp_path``; the
    commands' caches go to the per-user cache): ``make test`` wrote ``results/`` before."""
    if _checkout_before is None or hasattr(session.config, "workerinput"):
        return
    after = _untracked()
    new = sorted((after or set()) - _checkout_before)
    if new:
        print(f"\nerror: the tests wrote into the checkout {REPO}: {', '.join(new[:5])}")
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
