"""Ctrl-C and SIGTERM: end the run cleanly at a safe point, never inside native code.

FMPy's CVode wrapper calls back into Python through ctypes for every right-hand side. A
``KeyboardInterrupt`` raised inside such a callback is printed as "Exception ignored on
calling ctypes callback function" and swallowed: the run goes on and exits 0 with a result
that differs from an uninterrupted one. So around the solver loop (``deferred()``) the signal
handler only records the signal, and the loop calls ``check()`` between solver steps, where
raising is safe: ``finally`` blocks free the FMU and remove temporary files, nothing is
written, and the command line turns :class:`Interrupted` into one line and exit status 130.

Outside ``deferred()``, ``install()`` makes SIGTERM behave like Ctrl-C (Python's default
for SIGTERM ends the process without running ``finally`` blocks, leaving part files).
"""

from __future__ import annotations

import contextlib
import functools
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from types import FrameType
from typing import ParamSpec, TypeVar

_P = ParamSpec("_P")
_R = TypeVar("_R")

#: The signals that end a run.
SIGNALS = (signal.SIGINT, signal.SIGTERM)
#: Exit status of a run ended by one of them (the shell's 128 + SIGINT).
EXIT_STATUS = 130

_pending: list[int] = []
#: Set once the run has reported its interruption and is only returning: a signal then is
#: recorded, never raised (it landed in a ``with`` block's exit, after the report).
_ending = [False]


class Interrupted(KeyboardInterrupt):
    """The run was ended by SIGINT or SIGTERM (a ``KeyboardInterrupt``, so ``except
    Exception`` in library code does not swallow it)."""

    def __init__(self, signum: int) -> None:
        self.signum = signum
        super().__init__(signal.Signals(signum).name)


def _in_main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def _unwinding() -> bool:
    """Whether this thread is unwinding from an interruption (in an ``except`` or
    ``finally`` block that an :class:`Interrupted` or Ctrl-C's ``KeyboardInterrupt`` runs)."""
    return isinstance(sys.exc_info()[1], KeyboardInterrupt)


def _raise(signum: int, frame: FrameType | None) -> None:
    """Raise the signal as :class:`Interrupted`; while the run is unwinding from one, a
    second signal is only recorded (SIGTERM then SIGINT 1 ms later raised again inside the
    ``finally`` that was removing a part file, and left it) and a third raises (the user
    insists)."""
    if _ending[0]:
        _pending.append(signum)
        return
    if _unwinding():
        _pending.append(signum)
        if len(_pending) < 2:
            return
    _pending.clear()
    raise Interrupted(signum)


def ending() -> None:
    """The run has reported its interruption and only returns now: a further signal is
    recorded, not raised (a SIGINT 1 ms after SIGTERM raised in ``warnings.catch_warnings``'
    exit after the one-line report, a traceback and status 1 instead of 130)."""
    _ending[0] = True


def _record(signum: int, frame: FrameType | None) -> None:
    _pending.append(signum)


def install() -> None:
    """SIGINT and SIGTERM raise :class:`Interrupted` (main thread only; elsewhere a no-op)."""
    if _in_main_thread():
        _pending.clear()  # a signal left from an earlier run in this process is not this one's
        _ending[0] = False
        for signum in SIGNALS:
            signal.signal(signum, _raise)


@contextlib.contextmanager
def deferred() -> Iterator[None]:
    """Within the block a signal is only recorded; ``check()`` raises it at a safe point.

    On leaving the block the previous handlers are back and a signal still pending is raised.
    Off the main thread (where Python cannot set handlers) the block changes nothing.
    """
    if not _in_main_thread():
        yield
        return
    previous = {signum: signal.getsignal(signum) for signum in SIGNALS}
    for signum in SIGNALS:
        signal.signal(signum, _record)
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
    check()


def deferring(function: Callable[_P, _R]) -> Callable[_P, _R]:
    """Decorator: run ``function`` inside ``deferred()`` (it calls ``check()`` in its loop)."""

    @functools.wraps(function)
    def wrapper(*args: _P.args, **kwargs: _P.kwargs) -> _R:
        with deferred():
            return function(*args, **kwargs)

    return wrapper


def check() -> None:
    """Raise :class:`Interrupted` if a signal arrived since the last check (while unwinding
    from an interruption, only if two did: one more changes nothing, see ``_raise``)."""
    if _pending and not (_unwinding() and len(_pending) < 2):
        signum = _pending[0]
        _pending.clear()
        raise Interrupted(signum)


def ignore_further() -> None:
    """Ignore SIGINT and SIGTERM from now on (main thread only): for a process whose run has
    ended by a signal and is exiting, where a second Ctrl-C would otherwise kill it by the
    default action during interpreter shutdown (exit -2 instead of 130)."""
    if _in_main_thread():
        for signum in SIGNALS:
            signal.signal(signum, signal.SIG_IGN)
