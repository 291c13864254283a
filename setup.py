"""Ships the repository's data with a non-editable install (``pip install .``).

The FMU, the Modelica source and the scenarios live at the top of the repository, where the
build and the users edit them. A wheel copies them into ``spindlebench/_data``, where
``spindlebench.core.paths`` finds them when the package is not run from a checkout. An editable
install needs no copy: ``spindlebench.core.paths`` uses the checkout itself.
"""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
#: (folder, file patterns) copied into the wheel's spindlebench/_data.
DATA = (("fmus", ("SpindleBench.fmu",)), ("models", ("*.mo", "*.csv")),
        ("scenarios", ("*.toml", "*.csv", "*.md")), ("benchmarks", ("*.toml",)))


class BuildWithData(build_py):
    """``build_py`` that also copies the package data into the build tree."""

    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):
            return
        target = Path(self.build_lib) / "spindlebench" / "_data"
        for folder, patterns in DATA:
            for pattern in patterns:
                for source in sorted((ROOT / folder).rglob(pattern)):
                    destination = target / source.relative_to(ROOT)
                    destination.parent.mkdir(parents=True, exist_ok=True)
                    shutil.copy2(source, destination)


setup(cmdclass={"build_py": BuildWithData})
