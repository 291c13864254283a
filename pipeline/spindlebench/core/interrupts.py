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

A signal can also land while a destructor runs: the garbage collector calls FMPy's
``CVodeSolver.__del__`` at any bytecode, and Python prints an exception raised there as
"Exception ignored in ..." and goes on. A sweep under load lost its Ctrl-C that way and
finished with status 0. So the handler does not raise inside a ``__del__``: it delivers the
signal again (``_redeliver``), and it raises at the first bytecode of ordinary code. Any
other place Python swallows it (a weakref callback, a ctypes callback outside
``deferred()``) reaches ``sys.unraisablehook``, which ``install()`` sets to do the same.
"""

from __future__ import annotations

import _thread
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
    insists). Inside a destructor, where Python would swallow it, it is delivered again at
    the next bytecode instead (:func:`_swallowed_here`)."""
    if _ending[0]:
        _pending.append(signum)
        return
    if _swallowed_here(frame):
        _redeliver(signum)
        return
    if _unwinding():
        _pending.append(signum)
        if len(_pending) < 2:
            return
    _pending.clear()
    raise Interrupted(signum)


#: Functions an exception raised in is printed and dropped by Python, not propagated.
_SWALLOWING = frozenset({"__del__", "_redelivering_hook"})


def _swallowed_here(frame: FrameType | None) -> bool:
    """Whether ``frame`` runs inside a destructor (or the hook below): an exception raised
    there never reaches the run."""
    while frame is not None:
        if frame.f_code.co_name in _SWALLOWING:
            return True
        frame = frame.f_back
    return False


def ending() -> None:
    """The run has reported its interruption and only returns now: a further signal is
    recorded, not raised (a SIGINT 1 ms after SIGTERM raised in ``warnings.catch_warnings``'
    exit after the one-line report, a traceback and status 1 instead of 130)."""
    _ending[0] = True


def _record(signum: int, frame: FrameType | None) -> None:
    _pending.append(signum)


def install() -> None:
    """SIGINT and SIGTERM raise :class:`Interrupted` (main thread only; elsewhere a no-op),
    also when they land in a destructor (``_redeliver``)."""
    if _in_main_thread():
        _pending.clear()  # a signal left from an earlier run in this process is not this one's
        _ending[0] = False
        for signum in SIGNALS:
            signal.signal(signum, _raise)
        if getattr(sys.unraisablehook, "__wrapped__", None) is None:
            sys.unraisablehook = _redelivering(sys.unraisablehook)


def _redelivering(previous: Callable[[object], object]) -> Callable[[object], object]:
    """``sys.unraisablehook`` that gives a swallowed :class:`Interrupted` back to the main
    thread and passes everything else to ``previous``."""

    @functools.wraps(previous)
    def _redelivering_hook(unraisable: object) -> object:
        exc = getattr(unraisable, "exc_value", None)
        if isinstance(exc, Interrupted) and _in_main_thread():
            _redeliver(exc.signum)
            return None
        return previous(unraisable)

    return _redelivering_hook


#: How long after a swallowed signal it is delivered again (the destructor is then done).
REDELIVER_AFTER_S = 0.001


def _redeliver(signum: int) -> None:
    """Signal ``signum`` to the main thread again, a moment from now and from another
    thread: Python runs its handler at the main thread's next bytecode then, no longer inside
    the destructor that would swallow it (if it still is, or in another one, this repeats).
    Not from this thread: a handler that re-signals itself at once runs again at once, inside
    the same destructor. ``interrupt_main`` only calls a Python-level handler, never the
    default action. Not a daemon thread: the interpreter joins it at exit (a millisecond),
    where a daemon thread still alive can crash the finalising interpreter (gh-110052)."""
    timer = threading.Timer(REDELIVER_AFTER_S, _thread.interrupt_main, (signum,))
    timer.start()


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
