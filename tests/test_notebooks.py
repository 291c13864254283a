"""The course notebooks execute from top to bottom (the real commands, the real FMU).

Each notebook runs in a fresh kernel of this venv (``spindlebench.course.execute``, as
``make notebooks`` does), in a temporary working folder. A failing cell fails the test with
the cell and its traceback.
"""

import pytest
from spindlebench.course import NOTEBOOKS, execute, notebook_files

NOTEBOOK_FILES = notebook_files()


def test_the_course_has_its_notebooks():
    assert [p.name[:2] for p in NOTEBOOK_FILES] == [f"{i:02d}" for i in
                                                     range(1, len(NOTEBOOK_FILES) + 1)]
    assert len(NOTEBOOK_FILES) >= 2, NOTEBOOKS


@pytest.mark.parametrize("path", NOTEBOOK_FILES, ids=[p.stem for p in NOTEBOOK_FILES])
def test_notebook_executes_and_shows_figures_and_ends_with_exercises(path, tmp_path):
    notebook = execute(path, tmp_path)
    outputs = [out for cell in notebook.cells if cell.cell_type == "code"
               for out in cell.outputs]
    assert not [out for out in outputs if out.output_type == "error"]
    assert sum("image/png" in out.get("data", {}) for out in outputs) >= 2
    assert "## Exercises" in notebook.cells[-1].source
    assert notebook.cells[0].cell_type == "markdown"  # plain words first
