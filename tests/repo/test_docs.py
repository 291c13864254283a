"""The documentation site builds with no warning (``mkdocs build --strict``: no broken link, no
missing page), its generated pages cover what they describe, and it opens without a server."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import REPO

HREF = re.compile(r'(?:href|src)="([^"]+)"')


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    result = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--quiet",
                             "-f", str(REPO / "mkdocs.yml"), "-d", str(out)],
                            cwd=REPO, env=env, capture_output=True, text=True)
    assert result.returncode == 0, result.stderr[-3000:]
    return out


@pytest.mark.slow
def test_every_command_has_its_reference_generated_from_the_parser(site):
    from spindlebench.commands.main import COMMANDS, build_parser

    page = (site / "generated" / "commands.html").read_text(encoding="utf-8")
    parser = build_parser()
    for name in COMMANDS:
        assert f"spindlebench {name}</code>" in page, name
        first_option = next(a for a in parser.commands[name]._actions if a.option_strings)
        assert first_option.option_strings[0] in page


@pytest.mark.slow
def test_every_notebook_and_machine_has_a_page(site):
    from spindlebench.machines.variants import machine_names

    for notebook in sorted((REPO / "notebooks").glob("[0-9][0-9]_*.py")):
        assert (site / "generated" / "course" / f"{notebook.stem}.html").is_file(), notebook
    machines = (site / "generated" / "machines.html").read_text(encoding="utf-8")
    for name in machine_names():
        assert f"<code>{name}</code>" in machines


@pytest.mark.slow
def test_the_site_opens_from_files_every_link_is_relative_and_resolves(site):
    # 404.html is for a web server (mkdocs roots its links there on purpose)
    pages = sorted(p for p in site.rglob("*.html") if p.name != "404.html")
    assert len(pages) > 15
    for page in pages:
        text = page.read_text(encoding="utf-8")
        for target in HREF.findall(text):
            if target.startswith(("http://", "https://", "mailto:", "#", "data:")):
                continue
            assert not target.startswith("/"), f"{page.relative_to(site)}: {target}"
            path = target.split("#")[0].split("?")[0]
            if path:
                assert (page.parent / path).resolve().exists(), \
                    f"{page.relative_to(site)} links to missing {target}"
