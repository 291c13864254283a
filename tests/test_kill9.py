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
             cwd: Path) -> list[int]:
    """A clean run into ``reference``, then a chain of KILLS seeded kills and a final run
    into ``out`` (``argv`` names ``{out}``); returns the statuses of the killed runs."""
    code, clean_cpu = zygote.run([a.replace("{out}", str(reference)) for a in argv], cwd,
                                 kill_at_cpu_s=float("inf"))  # measured, never killed
    assert code == 0
    moments = random.Random(seed).sample(range(1, 100), KILLS)
    statuses = []
    for percent in moments:
        code, _ = zygote.run([a.replace("{out}", str(out)) for a in argv], cwd,
                             kill_at_cpu_s=clean_cpu * percent / 100)
        statuses.append(code)
    code, _ = zygote.run([a.replace("{out}", str(out)) for a in argv], cwd)
    assert code == 0, statuses
    return statuses
