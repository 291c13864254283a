"""Issue 25: ``kill -9`` of ``sweep``, ``place``, ``compensate`` and ``calibrate`` at seeded
random moments, each chain then resumed to the bytes of an uninterrupted run.

A chain: start the command, SIGKILL it once it has used a seeded random share of the CPU
time of a clean run (CPU, not wall seconds: on a loaded machine the same moment of the
work), start it again on what is left, kill it again, ... ten times, then let it finish, and
compare every file with the clean run's. The runs are forked from one process that has
imported the package already (a "zygote"): a fresh interpreter's imports would cost more CPU
than the tiny studies themselves, and the process that is killed runs the command's real
code from ``main`` on, with its own pid, files and exit.
"""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import REPO

KILLS = 10
STUDIES = REPO / "scenarios" / "studies"

ZYGOTE = r"""
import json, os, sys
from spindlebench.commands import main as cli
# what the four commands import when they run: loaded once here, not in every forked run
import spindlebench.commands.sweep, spindlebench.commands.place
import spindlebench.commands.compensate, spindlebench.commands.calibrate
import spindlebench.studies.sweep.sweep_run, spindlebench.studies.placement.placement_run
import spindlebench.studies.compensation.loop
import spindlebench.studies.compensation.compensation_report
import spindlebench.calibration.problem, spindlebench.calibration.fit_report
import spindlebench.model.equations, spindlebench.studies.sweep.sweep_report
import spindlebench.studies.sweep.sweep_plots, spindlebench.studies.placement.placement_report
print("ready", flush=True)
for line in sys.stdin:
    request = json.loads(line)
    pid = os.fork()
    if pid == 0:
        null = os.open(os.devnull, os.O_RDWR)
        for fd in (0, 1, 2):
            os.dup2(null, fd)
        os.chdir(request["cwd"])
        try:
            code = cli.main(request["argv"])
        except BaseException:
            code = 99
        os._exit(code)
    print("pid", pid, flush=True)
    _, status = os.waitpid(pid, 0)
    print("exit", os.waitstatus_to_exitcode(status), flush=True)
"""


class Zygote:
    """A process with the package imported that forks one command run per request."""

    def __init__(self) -> None:
        self.process = subprocess.Popen([sys.executable, "-c", ZYGOTE], stdin=subprocess.PIPE,
                                        stdout=subprocess.PIPE, text=True)
        assert self.process.stdout.readline().strip() == "ready"

    def run(self, argv: list[str], cwd: Path, kill_at_cpu_s: float | None = None
            ) -> tuple[int, float]:
        """Run ``argv``; SIGKILL it once it has used ``kill_at_cpu_s`` of CPU. Returns its
        exit status (-9 when killed) and the CPU seconds it used."""
        self.process.stdin.write(json.dumps({"argv": argv, "cwd": str(cwd)}) + "\n")
        self.process.stdin.flush()
        word, pid = self.process.stdout.readline().split()
        assert word == "pid"
        pid, used = int(pid), 0.0
        while kill_at_cpu_s is not None:
            now = cpu_s(pid)
            if now is None:  # ended (a zombie until the zygote reaps it)
                break
            used = now
            if used >= kill_at_cpu_s:
                os.kill(pid, signal.SIGKILL)
                break
            time.sleep(0.002)
        word, code = self.process.stdout.readline().split()
        assert word == "exit"
        return int(code), used

    def close(self) -> None:
        self.process.stdin.close()
        self.process.wait(timeout=60)


def cpu_s(pid: int) -> float | None:
    """CPU seconds (user + system) of a running process; None once it has ended."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    if fields[0] in ("Z", "X"):
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


@pytest.fixture(scope="module")
def zygote():
    z = Zygote()
    yield z
    z.close()


def files_of(folder: Path, exclude: tuple[str, ...] = ()) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and p.name != ".lock" and p.name not in exclude}


def campaign(zygote: Zygote, argv: list[str], out: Path, reference: Path, seed: int,
             cwd: Path, share: float) -> list[int]:
    """A clean run into ``reference``, then a chain of KILLS runs into ``out`` (``argv``
    names ``{out}``), each killed at a seeded random moment within ``share`` of the clean
    run's CPU time, and a final run; returns the statuses of the killed runs."""
    code, clean_cpu = zygote.run([a.replace("{out}", str(reference)) for a in argv], cwd,
                                 kill_at_cpu_s=float("inf"))  # measured, never killed
    assert code == 0
    moments = random.Random(seed).sample(range(1, 100), KILLS)
    statuses = []
    for percent in moments:
        code, _ = zygote.run([a.replace("{out}", str(out)) for a in argv], cwd,
                             kill_at_cpu_s=clean_cpu * share * percent / 100)
        statuses.append(code)
    code, _ = zygote.run([a.replace("{out}", str(out)) for a in argv], cwd)
    assert code == 0, statuses
    return statuses


def small_sweep(folder: Path) -> Path:
    """tiny_sweep.toml on one replica (4 runs): the chain costs CPU, not coverage."""
    text = (STUDIES / "tiny_sweep.toml").read_text(encoding="utf-8")
    assert "replicas = 2" in text
    study = folder / "sweep.toml"
    study.write_text(text.replace("replicas = 2", "replicas = 1"), encoding="utf-8")
    return study


def small_placement(folder: Path) -> Path:
    """tiny_placement.toml cut to one month, one budget, two methods."""
    text = (STUDIES / "tiny_placement.toml").read_text(encoding="utf-8")
    for old, new in (('months = ["Jan", "Jul"]', 'months = ["Jan"]'),
                     ("budgets = [2, 3]", "budgets = [2]"),
                     ('methods = ["fuzzy", "greedy", "exhaustive", "kmeans+grey", "lasso"]',
                      'methods = ["fuzzy", "greedy"]'),
                     ("with_differences = [false, true]", "with_differences = [false]")):
        assert old in text
        text = text.replace(old, new)
    study = folder / "place.toml"
    study.write_text(text, encoding="utf-8")
    return study


TWIN = """description = "kill -9 calibration twin"
duration_s = 3600
step_s = 60.0
sample_interval_s = 60.0
seed = 5
[speed]
kind = "steps"
steps = [{at_s = 0, rpm = 6000}, {at_s = 1800, rpm = 0}]
[feed]
kind = "with_spindle"
x_mm_per_min = 1500
y_mm_per_min = 1500
[ambient]
kind = "season"
low_C = 19
high_C = 22
"""


def command_line(command: str, folder: Path, zygote: Zygote) -> list[str]:
    """The command's arguments (``{out}`` for the output) and what it reads, made here."""
    if command == "sweep":
        return ["sweep", str(small_sweep(folder)), "-o", "{out}", "--workers", "0",
                "--no-progress"]
    if command == "place":
        return ["place", str(small_placement(folder)), "-o", "{out}", "--workers", "0",
                "--no-progress"]
    if command == "compensate":
        return ["compensate", str(STUDIES / "tiny_compensate.toml"), "-o", "{out}", "-q"]
    from spindlebench.calibration.mapping import recording_map_text

    (folder / "twin.toml").write_text(TWIN, encoding="utf-8")
    (folder / "map.toml").write_text(recording_map_text(["T1", "T4"]), encoding="utf-8")
    assert zygote.run(["simulate", str(folder / "twin.toml"), "-o", str(folder / "twin.csv")],
                      folder)[0] == 0
    argv = ["calibrate", str(folder / "twin.csv"), "--map", str(folder / "map.toml"), "-o",
            "{out}/twin.toml", "--models", str(REPO / "models"), "--fit",
            "front_bearing_friction_f0", "-q"]
    # the translated model is cached on disk (model.ode_cache): a run first, so the clean
    # run whose CPU sets the kill moments costs what every run of the chain costs
    warm = [a.replace("{out}", str(folder / "warm")) for a in argv]
    assert zygote.run(warm, folder)[0] == 0
    return argv


#: Per command: whether it resumes (finished work kept: each run of the chain is killed
#: within a quarter of a clean run's CPU, so the chain moves through the whole work).
RESUMES = {"sweep": True, "place": True, "compensate": False, "calibrate": False}


def without_wall_times(files: dict[str, bytes]) -> dict[str, bytes]:
    """The one field that legitimately differs between two correct runs: calibrate's report
    gives the fit's wall ``seconds``. Every other byte of every command's output is compared."""
    name = "twin.calibration.json"
    if name in files:
        report = json.loads(files[name])
        assert isinstance(report.pop("seconds"), float)
        files[name] = json.dumps(report, sort_keys=True).encode()
    return files


@pytest.mark.slow
@pytest.mark.parametrize("command", ["sweep", "place", "compensate", "calibrate"])
def test_kill_9_at_ten_seeded_moments_then_a_resume_gives_the_clean_runs_bytes(
        tmp_path, zygote, command):
    argv = command_line(command, tmp_path, zygote)
    out, reference = tmp_path / "killed", tmp_path / "clean"
    statuses = campaign(zygote, argv, out, reference, seed=sum(map(ord, command)),
                        cwd=tmp_path, share=0.25 if RESUMES[command] else 1.0)
    assert statuses.count(-signal.SIGKILL) >= KILLS // 2, statuses  # killed, not finished
    assert without_wall_times(files_of(out)) == without_wall_times(files_of(reference))
