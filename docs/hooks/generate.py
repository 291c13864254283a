"""MkDocs hook: the pages that are generated from the code and files they describe.

A page typed by hand goes stale at the next change of what it describes; these cannot. At every
``mkdocs build`` (``make docs``) this hook adds, under ``generated/``:

- ``commands.md``: every sub-command's ``--help``, from the argument parser itself;
- ``methods.md``: the selection methods, from the method registry (``spindlebench methods``);
- ``machines.md``: every shipped machine file, its description, parameters and targets;
- ``scenarios.md``: ``scenarios/README.md``, the scenario schema's own documentation;
- ``course/``: each notebook of ``notebooks/`` as a page (its text and code, from the jupytext
  source), with the executed notebook (figures and outputs) beside it when ``make notebooks``
  has written it to ``results/notebooks/`` (``make docs`` runs it first);
- ``results/``: the READMEs that ``make run`` writes (the paper's comparison on the synthetic
  experiments and on the real recording), with their figures and tables, and any study results
  folder listed in ``RESULT_FOLDERS`` that exists: the result tables of the site are the files
  the commands wrote, not copies typed by hand;
- in every page, each ``<!-- generate: NAME KEY -->`` line becomes a table generated from the
  file a command wrote, with its source beside it (``tables.py``: the speed page from
  ``bench/results/*.json``, the model page's fingerprints, mechanisms, levels and parameters,
  the stable-room study tables).
"""

from __future__ import annotations

import html
import logging
import sys
from pathlib import Path

from mkdocs.structure.files import File, Files

sys.path.insert(0, str(Path(__file__).resolve().parent))
import tables  # the hooks folder is not a package: imported from its path

LOG = logging.getLogger("mkdocs.hooks.spindlebench")
ROOT = Path(__file__).resolve().parents[2]
EXECUTED = ROOT / "results" / "notebooks"
#: Results folders whose README becomes a page (site path -> folder), when they exist.
RESULT_FOLDERS = {
    "generated/results/paper_study": ROOT / "results" / "paper_study",
    "generated/results/caiviac_study": ROOT / "results" / "caiviac_study",
    "generated/results/population": ROOT / "results" / "population",
    "generated/results/placement-stable-room": ROOT / "results" / "placement-stable-room"
                                                / "population",
    "generated/results/compensate-stable-room": ROOT / "results" / "compensate-stable-room"
                                                 / "population",
    "generated/results/season-sweep": ROOT / "results" / "season-sweep",
    "generated/results/season-sweep-methods": ROOT / "results" / "season-sweep-methods",
    "generated/results/af-sweep": ROOT / "results" / "af-sweep",
}
#: A results folder's committed copy (``make docs-snapshots``), shown when the folder is not in
#: this checkout's results/: the same path under docs/snapshots/.
SNAPSHOTS = ROOT / "docs" / "snapshots"
#: What writes each results folder (for the page shown when it is not there).
RESULT_COMMANDS = {
    "season-sweep": tables.SWEEP_FOLDERS["season-sweep"],
    "season-sweep-methods": tables.SWEEP_FOLDERS["season-sweep-methods"],
    "af-sweep": tables.SWEEP_FOLDERS["af-sweep"],
    "placement-stable-room": tables.STUDY_COMMANDS["placement-population"],
    "compensate-stable-room": tables.STUDY_COMMANDS["compensation-population"],
}


def on_page_markdown(markdown: str, page, config, files) -> str:
    """Each ``<!-- generate: ... -->`` line of a page becomes its generated table."""
    return tables.expand(markdown)


def on_files(files: Files, config) -> Files:
    """Add every generated page (mkdocs calls this once per build, before reading pages)."""
    pages = {
        "generated/commands.md": commands_page(),
        "generated/methods.md": methods_page(),
        "generated/machines.md": machines_page(),
        "generated/scenarios.md": scenarios_page(),
    }
    pages.update(course_pages(files, config))
    pages.update(result_pages(files, config))
    for uri, text in pages.items():
        files.append(File.generated(config, uri, content=text))
    return files


def commands_page() -> str:
    """Every sub-command's help, as ``spindlebench CMD --help`` prints it."""
    from spindlebench.commands.main import COMMANDS, build_parser

    parser = build_parser()
    lines = ["# Command reference", "",
             "Generated from the argument parser (`spindlebench CMD --help` prints the same).",
             "", "```text", parser.format_help().rstrip(), "```", ""]
    for name in sorted(COMMANDS):
        sub = parser.commands[name]
        lines += [f"## `spindlebench {name}`", "", "```text", sub.format_help().rstrip(), "```",
                  ""]
    return "\n".join(lines)


def methods_page() -> str:
    """The method listing of the registry (what ``spindlebench methods`` prints)."""
    from spindlebench.selection.registry import listing

    return "\n".join(["# Selection methods", "",
                      "Generated from the method registry (`spindlebench methods` prints the "
                      "same). Every name here is accepted by `evaluate --method`, the paper "
                      "configuration and the study files.", "", "```text", listing().rstrip(),
                      "```", ""])


def machines_page() -> str:
    """Each shipped machine: description, parameters set on top of the FMU's, targets."""
    from spindlebench.machines.variants import load_machine, machine_names

    lines = ["# Machines", "",
             "Generated from `scenarios/machines/*.toml`. A machine is a named set of FMU "
             "parameter values on top of the model's defaults, with the fingerprint targets "
             "its runs were checked against (`tests/machines/test_machines.py`). Any command that "
             "simulates takes `--machine NAME` or a path to a machine file.", ""]
    for name in machine_names():
        machine = load_machine(name)
        lines += [f"## `{name}`", "", machine.description.strip(), ""]
        if machine.parameters:
            lines += [tables.machine_parameters_section(machine.path)]
        else:
            lines += ["Parameters: the FMU's defaults.", ""]
        if machine.targets:
            lines += ["Targets:", ""] + [f"- {t.describe()}" for t in machine.targets] + [""]
    return "\n".join(lines)


def scenarios_page() -> str:
    """``scenarios/README.md``: the schema of a scenario, kept beside the scenarios."""
    return (ROOT / "scenarios" / "README.md").read_text(encoding="utf-8")


def course_pages(files: Files, config) -> dict[str, str]:
    """One page per notebook (text and code from its jupytext source), the executed HTML
    beside it when it exists, and the course's index."""
    import jupytext

    index = ["# The course", "",
             "Short notebooks that teach thermal error and sensor selection with the "
             "testbench; each ends with exercises. `make notebooks` executes them "
             "(`results/notebooks/`); `make docs` does so first and puts each executed "
             "notebook, with its figures, beside its page.", ""]
    pages: dict[str, str] = {}
    for source in sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.py")):
        notebook = jupytext.reads(source.read_text(encoding="utf-8"), fmt="py:percent")
        title = _title(notebook, source.stem)
        executed = EXECUTED / f"{source.stem}.html"
        body = [f"# {html.escape(title)}", ""]
        if executed.is_file():
            files.append(File.generated(config, f"generated/course/{executed.name}",
                                        abs_src_path=str(executed)))
            body += [f"[The executed notebook, with its figures and outputs]({executed.name})",
                     ""]
        else:
            LOG.info("no executed %s: run make notebooks to show its outputs", executed.name)
            body += ["*(Outputs are not included in this build: `make docs` executes the "
                     "notebooks first.)*", ""]
        for cell in notebook.cells:
            text = cell.source.strip()
            if not text:
                continue
            if cell.cell_type == "markdown":
                body += [_drop_first_title(text) if cell is notebook.cells[0] else text, ""]
            else:
                body += ["```python", text, "```", ""]
        pages[f"generated/course/{source.stem}.md"] = "\n".join(body)
        index.append(f"- [{title}]({source.stem}.md)")
    pages["generated/course/index.md"] = "\n".join(index) + "\n"
    return pages


def _title(notebook, fallback: str) -> str:
    for cell in notebook.cells:
        if cell.cell_type == "markdown":
            for line in cell.source.splitlines():
                if line.startswith("# "):
                    return line[2:].strip()
    return fallback


def _drop_first_title(text: str) -> str:
    lines = text.splitlines()
    if lines and lines[0].startswith("# "):
        lines = lines[1:]
    return "\n".join(lines).strip()


def result_pages(files: Files, config) -> dict[str, str]:
    """Each existing results folder's README as a page, its figures and tables beside it, and
    an index that says which command writes each (or that it has not been run)."""
    pages: dict[str, str] = {}
    index = ["# Results written by the commands", "",
             "These pages are the READMEs the commands wrote, as they wrote them (figures and "
             "tables beside them). `make run` writes the first two; `make docs` runs it when "
             "`results/README.md` is missing.", ""]
    for uri, folder in RESULT_FOLDERS.items():
        readme = folder / "README.md"
        name = uri.rsplit("/", 1)[1]
        snapshot = SNAPSHOTS / folder.relative_to(ROOT / "results") / "README.md"
        if not readme.is_file() and snapshot.is_file():
            folder, readme = snapshot.parent, snapshot  # its committed copy (no figures)
        if not readme.is_file():  # a page all the same, so the links to it hold
            command = RESULT_COMMANDS.get(name)
            pages[f"{uri}/index.md"] = (
                f"# {name}\n\nNot run in this build: `{command}` writes it.\n" if command else
                f"# {name}\n\nNot run in this build: `make run` writes "
                f"`results/{name}/` (`make docs` runs it first).\n")
            index.append(f"- [{name}]({name}/index.md): not run in this build")
            continue
        for item in sorted(folder.iterdir()):
            if item.is_file() and item.suffix in (".png", ".csv", ".json", ".md") and \
                    item.name != "README.md":
                files.append(File.generated(config, f"{uri}/{item.name}",
                                            abs_src_path=str(item)))
        text = readme.read_text(encoding="utf-8")
        source = tables.Sources().name(readme)
        copy = readme.is_relative_to(SNAPSHOTS)
        note = (f"*The committed snapshot `{source}` (`make docs-snapshots` copies it from "
                "`results/`; this checkout has not run it).*\n\n" if copy else "")
        pages[f"{uri}/index.md"] = (f"<!-- tables copied from {source} -->\n\n" + note
                                    + _links_to_files(text, folder))
        index.append(f"- [{name}]({name}/index.md)" + (" (committed snapshot)" if copy else ""))
    pages["generated/results/index.md"] = "\n".join(index) + "\n"
    return pages


def _links_to_files(text: str, folder: Path) -> str:
    """A README's links to sub-folders or files the site does not carry become plain text, and
    so do its images that are not there (a snapshot keeps the README, not its figures): mkdocs
    --strict refuses a link to a file that is not in the site."""
    import re

    def keep(match: re.Match) -> str:
        target = match.group(3).split("#")[0]
        if target.startswith(("http://", "https://")) or not target:
            return match.group(0)
        path = folder / target
        if path.is_file() and path.parent == folder and \
                path.suffix in (".png", ".csv", ".json", ".md"):  # the files result_pages copies
            return match.group(0)
        what = "figure not in this build: " if match.group(1) else ""
        return f"{match.group(2)} ({what}`{target}`)"

    return re.sub(r"(!?)\[([^\]]*)\]\(([^)]+)\)", keep, text)
