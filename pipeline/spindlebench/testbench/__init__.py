"""The testbench half: scenarios (TOML) → drivers → FMU co-simulation → sensor model → recording.

``simulate_scenario`` is the one-call entry point used by the command line and the demo.

Importing this package is cheap: ``simulate_scenario`` is imported from ``simulate`` on first
use (PEP 562 ``__getattr__``), so reading a scenario (``testbench.scenario``, what every study
file loads) does not pull in FMPy, pandas and SciPy with the runner (~1.1 CPU-s of every
command's ``--help`` that reads study files).
"""

from __future__ import annotations

from typing import Any

__all__ = ["simulate_scenario"]


def __getattr__(name: str) -> Any:
    """``simulate_scenario``, imported from ``testbench.simulate`` on first use."""
    if name != "simulate_scenario":
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from spindlebench.testbench.simulate import simulate_scenario

    globals()[name] = simulate_scenario
    return simulate_scenario
