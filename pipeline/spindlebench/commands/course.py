"""The course: the notebooks in ``notebooks/``, executed and rendered to HTML.

The notebooks are stored as jupytext percent-format ``.py`` files, so a change to one is a
readable diff; ``jupytext`` turns one into a notebook, ``nbclient`` runs it in a fresh kernel
of the Python that runs this module (the project's venv, where ``ipykernel`` is pinned), and
``nbconvert`` writes it as HTML with its outputs. The test suite executes every notebook the
same way, so the course cannot rot. ``make notebooks`` calls::

    python -m spindlebench.commands.course results/notebooks

Each notebook writes its recordings and figures into its own working folder, which
``start`` makes (``<base>/<NN>``): ``base`` is the folder given to ``start``, else
``$SPINDLEBENCH_COURSE_DIR`` (``execute`` sets it to ``<out>/work/<notebook>`` for
``make notebooks`` and the tests), else ``course/`` in the per-user cache
(``core.paths.user_cache_dir``). Never the folder the notebook runs from, and nothing is deleted:
a student's own files beside the outputs stay (the commands replace only their own outputs).
It finds the shipped scenarios and the FMU through ``spindlebench.core.paths``.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from spindlebench.core import atomic
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import REPO_ROOT, user_cache_dir

#: The notebooks live in the checkout, beside the package (not in an installed wheel).
NOTEBOOKS = (REPO_ROOT or Path.cwd()) / "notebooks"
#: Names the folder the notebooks' working folders go into (see ``work_base``).
COURSE_DIR_ENV = "SPINDLEBENCH_COURSE_DIR"
#: Seconds one cell may take before the run is stopped as hung.
CELL_TIMEOUT_S = 600


def notebook_files(folder: Path = NOTEBOOKS) -> list[Path]:
    """The course's notebooks in order: ``NN_name.py``."""
    return sorted(folder.glob("[0-9][0-9]_*.py"))


def _figures_inline() -> None:
    """Select matplotlib's inline backend when running in a notebook kernel."""
    try:
        from IPython import get_ipython
    except ImportError:  # run as a plain script: nothing to show inline
        return
    shell = get_ipython()
    if shell is not None and "inline" not in matplotlib_backend():
        shell.run_line_magic("matplotlib", "inline")


def matplotlib_backend() -> str:
    import matplotlib

    return str(matplotlib.get_backend())


def spindlebench(*arguments: object) -> None:
    """Run a ``spindlebench`` command from a notebook, as on the command line:
    ``spindlebench("plot", "a.csv", "-o", "a.png")``. Paths may be ``Path`` objects. A
    command that fails (its one-line error is printed) raises, so the notebook stops there
    instead of running on without the command's output."""
    from spindlebench.commands.main import main

    words = [str(argument) for argument in arguments]
    status = main(words)
    _figures_inline()  # a command's figure modules may have selected Agg
    if status != 0:
        raise RuntimeError(f"spindlebench {' '.join(words)} failed (status {status})")


def work_base(base: str | Path | None = None) -> Path:
    """The folder the notebooks' working folders go into: ``base``, else
    ``$SPINDLEBENCH_COURSE_DIR``, else ``course/`` in the per-user cache."""
    if base is not None:
        return Path(base)
    return Path(os.environ.get(COURSE_DIR_ENV) or user_cache_dir() / "course")


def start(name: str, base: str | Path | None = None) -> Path:
    """Begin a notebook: its working folder ``<base>/<name>`` (see ``work_base``), made if
    missing and never emptied, and figures shown inline.

    It deleted ``work/<name>`` under the current folder before: a student's own files there
    were lost. Now nothing is deleted; each command of the notebook replaces its own outputs
    (atomically), a study resumes its folder. To start a notebook afresh, delete the folder
    it prints.

    The figure modules select matplotlib's file-only Agg backend when they are imported
    (some only when their command runs), which would hide the notebook's own figures; the
    inline backend is selected here and again after every ``spindlebench(...)`` command.
    """
    from spindlebench.commands.main import build_parser

    build_parser()  # imports every command module now, before the backend is chosen
    _figures_inline()
    folder = work_base(base) / name
    folder.mkdir(parents=True, exist_ok=True)
    print(f"this notebook writes its files into {folder}")
    return folder


def execute(path: Path, cwd: Path):
    """Run the notebook ``path`` with ``cwd`` as its working directory and the base of its
    working folder (``$SPINDLEBENCH_COURSE_DIR``); return it with its outputs. A failing cell
    raises ``nbclient.exceptions.CellExecutionError`` naming it."""
    import jupytext
    from nbclient import NotebookClient

    notebook = jupytext.read(path)
    cwd.mkdir(parents=True, exist_ok=True)
    client = NotebookClient(notebook, timeout=CELL_TIMEOUT_S, kernel_name="python3",
                            resources={"metadata": {"path": str(cwd)}})
    client.execute(env={**os.environ, COURSE_DIR_ENV: str(cwd)})
    return notebook


def render(out_dir: Path, folder: Path = NOTEBOOKS) -> list[Path]:
    """Execute every notebook and write ``<out_dir>/<name>.html`` and an ``index.html``."""
    from nbconvert import HTMLExporter

    files = notebook_files(folder)
    if not files:
        raise SpindlebenchError(f"{folder}: no notebooks (NN_name.py) found")
    exporter = HTMLExporter()
    written = []
    for path in files:
        print(f"running {path.name} ...", flush=True)
        notebook = execute(path, out_dir / "work" / path.stem)
        html, _ = exporter.from_notebook_node(notebook)
        atomic.write_text(out_dir / f"{path.stem}.html", html)
        written.append(out_dir / f"{path.stem}.html")
    items = "\n".join(f'<li><a href="{p.name}">{p.stem.replace("_", " ")}</a></li>'
                      for p in written)
    atomic.write_text(out_dir / "index.html",
                      f"<!doctype html><meta charset='utf-8'><title>spindlebench course"
                      f"</title><h1>spindlebench course</h1><ol>\n{items}\n</ol>\n")
    return written


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("results/notebooks")
    for page in render(out):
        print(page)
