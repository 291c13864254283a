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


@pytest.fixture(scope="session")
def repo() -> Path:
    """The repository root."""
    return REPO
