"""Whether a local pool's run is started where its workers would start it again.

Each worker of a local pool (forkserver, as with ``spawn``) imports the main script before it
takes a task, as Python's multiprocessing does: a script that starts a run at its top level,
not under ``if __name__ == "__main__":``, starts it again in every worker. There it found the
results folder locked by the real run and died with a traceback, one per worker, and the run
reported only "worker process died" for every task. ``unguarded_main_line`` finds such a
script before the pool starts (the run then stops with one line); ``importing_main_in_a_worker``
is the worker's side, where the first test could not tell (the script's source unreadable).
"""

from __future__ import annotations

import ast
import multiprocessing
import sys
from pathlib import Path


def importing_main_in_a_worker() -> bool:
    """Whether this process is a pool's worker still importing the main script
    (multiprocessing's own test, ``spawn._check_not_importing_main``)."""
    return bool(getattr(multiprocessing.current_process(), "_inheriting", False))


def unguarded_main_line() -> tuple[str, int] | None:
    """The main script and the line of its top level that is running now, where that line
    is not under ``if __name__ == "__main__":`` (a worker would run it again); None where it
    is, or where there is no such script (a notebook, ``python -c``, the interpreter's
    prompt) or its source cannot be read (then nothing is said)."""
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if main is None or not isinstance(path, str) or not path.endswith(".py"):
        return None
    # multiprocessing's own rule (``spawn._fixup_main_from_name``): a package's __main__
    # (``python -m spindlebench``) is never imported again in a worker
    name = getattr(getattr(main, "__spec__", None), "name", None)
    if isinstance(name, str) and (name == "__main__" or name.endswith(".__main__")):
        return None
    frame = sys._getframe(1)
    line = None
    while frame is not None:  # the outermost frame of the script's own top level
        if frame.f_globals is vars(main) and frame.f_code.co_name == "<module>" \
                and frame.f_code.co_filename == path:
            line = frame.f_lineno
        frame = frame.f_back
    if line is None:
        return None
    try:
        tree = ast.parse(Path(path).read_text(encoding="utf-8"), filename=path)
    except (OSError, UnicodeDecodeError, SyntaxError, ValueError):
        return None
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and _tests_main(node.test) \
                and node.lineno <= line <= (node.end_lineno or node.lineno):
            return None
    return path, line


def _tests_main(test: ast.expr) -> bool:
    """Whether ``test`` looks at ``__name__`` (``__name__ == "__main__"``, either way round,
    or within a longer condition): any such block counts as the guard, so that a script is
    never refused for a guard written another way (where the block runs in a worker after
    all, the worker's own test still says so)."""
    return any(isinstance(node, ast.Name) and node.id == "__name__" for node in ast.walk(test))


def guard_message(path: str, line: int | None = None) -> str:
    """The one line that says what to do."""
    where = f"{path}:{line}" if line is not None else path
    return (f"{where}: starts a run with worker processes at the script's top level, and each "
            "worker imports the script and would start it again; put the run under `if "
            "__name__ == \"__main__\":` (as Python's multiprocessing requires), or give "
            "workers=0")
