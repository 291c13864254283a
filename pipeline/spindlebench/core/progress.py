"""What a long command says while it works, on stderr (stdout keeps its results).

Every command that can run longer than a few seconds shows where it is: a bar with counts
and an estimate (tqdm) where the work is counted (simulations, solver evaluations), a line
per step where it is not (translating the model, compiling it, writing figures), and its
summary line reports the whole wall time. ``-q`` turns all of it off; commands without a
progress bar of their own (``build``, ``calibrate``, ``compensate``) speak only to a terminal
(``for_terminal``), as ``simulate``'s bar does, so a failing command's stderr stays its one
error line in logs and tests.
"""

from __future__ import annotations

import sys
import time
from typing import Any


class Stages:
    """One line per step of a long command: ``label: what (12 s so far)`` on stderr."""

    def __init__(self, label: str, enabled: bool = True) -> None:
        self.label = label
        self.enabled = enabled
        self.started = time.perf_counter()

    @property
    def seconds(self) -> float:
        """Wall time since the command started."""
        return time.perf_counter() - self.started

    def __call__(self, what: str) -> None:
        if self.enabled:
            print(f"{self.label}: {what} ({self.seconds:.0f} s so far)", file=sys.stderr,
                  flush=True)


def for_terminal(quiet: bool) -> bool:
    """Whether a command's step lines are wanted: not ``-q`` and stderr is a terminal."""
    return not quiet and sys.stderr.isatty()


def bar(total: int | None, desc: str, unit: str, enabled: bool = True) -> Any:
    """A tqdm bar on stderr (counts, rate and an estimate), or None when off."""
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit=f" {unit}", file=sys.stderr, leave=False,
                dynamic_ncols=True, delay=1.0)
