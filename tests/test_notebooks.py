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
    """name → the executed notebook, or the exception its execution raised."""
    def run(path):
        try:
            return execute(path, tmp_path_factory.mktemp(path.stem))
        except Exception as exc:  # reported by the notebook's own test
            return exc

    with ThreadPoolExecutor(max_workers=2) as pool:
        return dict(zip((p.stem for p in NOTEBOOK_FILES), pool.map(run, NOTEBOOK_FILES),
                        strict=True))


def test_the_course_has_its_seven_notebooks():
    assert [p.name[:2] for p in NOTEBOOK_FILES] == [f"{i:02d}" for i in range(1, 8)], NOTEBOOKS


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
    assert (out / "work" / "01_tiny" / "work" / "01").is_dir()  # ran in its own folder
