"""The README's set-up block: exactly two commands, one for the main job and one for the
tests, and ``.ci/run`` calls the second and no other make, pytest or python step (the
heading once said "Three commands" above two)."""

from __future__ import annotations

import re

from conftest import REPO


def _setup_block() -> tuple[str, list[str]]:
    """The heading of the README's first section with a code block, and its commands."""
    text = (REPO / "README.md").read_text(encoding="utf-8")
    for section in re.split(r"^## ", text, flags=re.M)[1:]:
        heading, _, body = section.partition("\n")
        block = re.search(r"^```\n(.*?)^```", body, re.M | re.S)
        if block:
            commands = [line.split("#", 1)[0].strip() for line in block.group(1).splitlines()]
            return heading.strip(), [command for command in commands if command]
    raise AssertionError("README.md: no section with a code block")


def test_the_readme_sets_up_with_two_commands_and_ci_runs_the_second():
    heading, commands = _setup_block()
    assert heading == "Two commands" and commands == ["make run", "make test"]
    ci = [line.strip() for line in (REPO / ".ci" / "run").read_text(encoding="utf-8")
          .splitlines() if line.strip() and not line.lstrip().startswith("#")]
    assert ci[-1] == commands[1], ci  # the last step is the README's test command
    assert not any(line.startswith(("make", "pytest", "python")) for line in ci[:-1]), ci
    makefile = (REPO / "Makefile").read_text(encoding="utf-8")
    for target in ("run", "test"):
        assert re.search(rf"^{target}:", makefile, re.M), f"Makefile: no '{target}' target"
