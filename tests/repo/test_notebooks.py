"""The course notebooks execute from top to bottom (the real commands, the real FMU).

Each notebook runs in a fresh kernel of this venv (``spindlebench.commands.course.execute``, as
``make notebooks`` does), in a temporary working folder. The kernels are single-threaded
work, so two notebooks run at a time (the machine has two cores); each test then checks
one notebook's result. A failing cell fails that notebook's test with its traceback.
"""

from concurrent.futures import ThreadPoolExecutor

import pytest
from spindlebench.commands.course import NOTEBOOKS, execute, notebook_files

NOTEBOOK_FILES = notebook_files()


@pytest.fixture(scope="module")
def executed(tmp_path_factory):
    """name → the executed notebook, or the exception its execution raised.

    The working folders are made here, before the threads start: pytest's
    ``tmp_path_factory`` is not thread-safe (two threads' first ``mktemp`` both create the
    worker's base folder, and the second fails with FileExistsError, as one CI run did).
    """
    folders = {p.stem: tmp_path_factory.mktemp(p.stem) for p in NOTEBOOK_FILES}

    def run(path):
        try:
            return execute(path, folders[path.stem])
        except Exception as exc:  # reported by the notebook's own test
            return exc

    with ThreadPoolExecutor(max_workers=2) as pool:
        return dict(zip(folders, pool.map(run, NOTEBOOK_FILES), strict=True))


def test_the_course_has_its_seven_notebooks():
    assert [p.name[:2] for p in NOTEBOOK_FILES] == [f"{i:02d}" for i in range(1, 8)], NOTEBOOKS


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOK_FILES, ids=[p.stem for p in NOTEBOOK_FILES])
def test_notebook_executes_and_shows_figures_and_ends_with_exercises(path, executed):
    notebook = executed[path.stem]
    if isinstance(notebook, Exception):
        raise notebook
    outputs = [out for cell in notebook.cells if cell.cell_type == "code"
               for out in cell.outputs]
    assert not [out for out in outputs if out.output_type == "error"]
    assert sum("image/png" in out.get("data", {}) for out in outputs) >= 2
    assert "## Exercises" in notebook.cells[-1].source
    assert notebook.cells[0].cell_type == "markdown"  # plain words first


@pytest.mark.slow  # a kernel start
def test_render_writes_each_notebook_as_html_with_its_figures_and_an_index(tmp_path):
    """``make notebooks`` (``spindlebench.commands.course.render``) on a one-cell course."""
    from spindlebench.commands.course import render

    course = tmp_path / "course"
    course.mkdir()
    (course / "01_tiny.py").write_text(
        "# %% [markdown]\n# # Tiny\n# %%\nfrom spindlebench.commands import course\n"
        "work = course.start('01')\nimport matplotlib.pyplot as plt\n"
        "plt.plot([1, 2])\nplt.show()\n", encoding="utf-8")
    (course / "notes.py").write_text("not a notebook: no NN_ prefix\n", encoding="utf-8")
    out = tmp_path / "html"
    assert render(out, course) == [out / "01_tiny.html"]
    html = (out / "01_tiny.html").read_text(encoding="utf-8")
    assert "<h1" in html and "data:image/png;base64" in html
    assert 'href="01_tiny.html"' in (out / "index.html").read_text(encoding="utf-8")
    assert (out / "work" / "01_tiny" / "01").is_dir()  # ran in its own folder


def test_start_keeps_a_students_files_and_writes_nothing_into_the_current_folder(
        tmp_path, monkeypatch):
    """``start`` emptied ``work/NN`` under the current folder on every run: a student's
    exercise files there were lost, and the outputs landed wherever the notebook ran."""
    from spindlebench.commands import course

    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    monkeypatch.setenv("SPINDLEBENCH_CACHE", str(tmp_path / "cache"))
    monkeypatch.delenv(course.COURSE_DIR_ENV, raising=False)
    folder = course.start("01")
    assert folder == tmp_path / "cache" / "course" / "01"
    (folder / "my_exercise.py").write_text("mine", encoding="utf-8")
    assert course.start("01") == folder
    assert (folder / "my_exercise.py").read_text(encoding="utf-8") == "mine"
    given = course.start("02", tmp_path / "given")
    assert given == tmp_path / "given" / "02" and given.is_dir()
    assert list(here.iterdir()) == []
