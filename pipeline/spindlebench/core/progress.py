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


def tqdm_class() -> Any:
    """tqdm's bar class, with its monitor thread switched off (the one home of that rule).

    tqdm starts a daemon "tqdm_monitor" thread that lives until the process ends. A daemon
    thread still alive while the interpreter finalises can crash it (CPython issue
    gh-110052, unfixed in 3.9-3.12): an interrupted sweep printed its one error line and then
    died of ``Fatal Python error: PyThreadState_Get`` with SIGABRT instead of exit 130. The
    monitor only shortens a bar's refresh interval after a stall; no bar here needs that.
    """
    from tqdm.auto import tqdm
    from tqdm.std import tqdm as std_tqdm

    std_tqdm.monitor_interval = 0
    if std_tqdm.monitor is not None:  # started by a bar made before this rule applied
        std_tqdm.monitor.exit()
        std_tqdm.monitor = None
    return tqdm


def bar(total: int | None, desc: str, unit: str, enabled: bool = True) -> Any:
    """A tqdm bar on stderr (counts, rate and an estimate), or None when off."""
    if not enabled:
        return None
    return tqdm_class()(total=total, desc=desc, unit=f" {unit}", file=sys.stderr, leave=False,
                dynamic_ncols=True, delay=1.0)
