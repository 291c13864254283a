"""The testbench half: scenarios (TOML) → drivers → FMU co-simulation → sensor model → recording.

``simulate_scenario`` is the one-call entry point used by the command line and the demo.
"""

from spindlebench.testbench.simulate import simulate_scenario

__all__ = ["simulate_scenario"]
