"""Issue 25: long work says what it does on stderr, off with ``-q``; summaries give the
whole wall time. ``build`` (162 s), and the post-processing after a study's progress bar
(a third of a sweep's wall time), printed nothing."""

from __future__ import annotations

import io
from pathlib import Path

from conftest import REPO
from spindlebench.commands import main as cli
from spindlebench.core.progress import Stages
from spindlebench.model import build

MINI = REPO / "scenarios" / "studies" / "tiny_placement.toml"


def test_build_names_each_of_its_four_steps(tmp_path, monkeypatch):
    heard: list[str] = []
    for name, fake in (("find_compiler", lambda: "cc"), ("validate", lambda source: []),
                       ("model_source", lambda folder: folder),
                       ("translate", lambda folder, segments: "flat"),
                       ("build_explicit_ode", lambda flat: "ode"),
                       ("export_fmu", lambda ode, out: Path(out))):
        monkeypatch.setattr(build, name, fake)
    out = build.build_fmu("models", tmp_path / "x.fmu", say=heard.append)
    assert out == tmp_path / "x.fmu"
    assert [line[:5] for line in heard] == ["[1/4]", "[2/4]", "[3/4]", "[4/4]"]
    assert "compiling" in heard[3]


def test_build_calibrate_and_compensate_speak_only_to_a_terminal(monkeypatch):
    import sys

    from spindlebench.core.progress import for_terminal

    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    assert for_terminal(quiet=False) and not for_terminal(quiet=True)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: False)
    assert not for_terminal(quiet=False)


def test_stages_print_on_stderr_with_the_time_so_far_and_stay_quiet_when_off(capsys):
    Stages("demo")("step one")
    Stages("demo", enabled=False)("never")
    out, err = capsys.readouterr()
    assert out == "" and err.startswith("demo: step one (") and "s so far)" in err
    assert "never" not in err


def study(tmp_path: Path) -> Path:
    path = tmp_path / "mini.toml"
    text = MINI.read_text(encoding="utf-8").replace('months = ["Jan", "Jul"]', 'months = ["Jan"]')
    text = text.replace("budgets = [2, 3]", "budgets = [2]").replace(
        'methods = ["fuzzy", "greedy", "exhaustive", "kmeans+grey", "lasso"]',
        'methods = ["fuzzy"]').replace("with_differences = [false, true]",
                                       "with_differences = [false]")
    path.write_text(text, encoding="utf-8")
    return path


def test_place_says_what_follows_its_bar_and_reports_the_whole_wall_time(tmp_path, capfd):
    mini = study(tmp_path)
    assert cli.main(["place", str(mini), "-o", str(tmp_path / "a"), "--workers", "0"]) == 0
    out, err = capfd.readouterr()
    for step in ("reading the simulated runs", "searching placements", "scoring",
                 "writing tables, figures"):
        assert f"tiny-placement: {step}" in err, err
    assert "s in all" in out.splitlines()[0]
    assert cli.main(["place", str(mini), "-o", str(tmp_path / "b"), "--workers", "0",
                     "-q"]) == 0
    out, err = capfd.readouterr()
    assert err == "" and "s in all" in out


def test_no_bar_leaves_a_daemon_thread_to_crash_the_interpreters_exit():
    """tqdm's monitor is a daemon thread; one alive at exit can abort the finalising
    interpreter (an interrupted sweep died of SIGABRT after its error line). Disabled bars
    start it too (in ``tqdm.__new__``), so every bar here must come without it."""
    import threading

    from spindlebench.core.progress import bar, tqdm_class

    with tqdm_class()(total=3, disable=True), tqdm_class()(total=3, file=io.StringIO()) as shown:
        shown.update(1)
        made = bar(3, "test", "x")
        made.close()
        assert not [t for t in threading.enumerate() if t.daemon and t.name == "tqdm_monitor"]


def test_a_redelivered_signal_is_sent_from_a_thread_the_interpreter_joins_at_exit(monkeypatch):
    import threading

    from spindlebench.core import interrupts

    sent = []
    monkeypatch.setattr(interrupts._thread, "interrupt_main", sent.append)
    before = set(threading.enumerate())
    interrupts._redeliver(2)
    timers = [t for t in threading.enumerate() if t not in before]
    for timer in timers:
        assert not timer.daemon
        timer.join(5)
    assert sent == [2]
