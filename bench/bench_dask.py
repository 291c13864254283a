"""Benchmark: the season sweep's CPU seconds on the local pool and on a real Dask cluster,
1 and 2 workers (issue 26: Dask within 1.2x the local pool's CPU).

The study is ``bench_sweep.bench_study``'s cut of the example season sweep (2 replicas, one
training run: 48 six-hour simulations and 14 evaluation jobs). Every configuration runs the
real command, ``spindlebench sweep STUDY -o DIR -q``, from scratch in its own folder:

- ``local``: ``--workers N`` (forkserver pool of N processes);
- ``dask``: a cluster of separate processes started here as docs/speed.md starts a study
  cluster, ``dask scheduler`` and ``dask worker --nworkers N --nthreads 1 ...
  --preload-nanny spindlebench.studies.running.dask_plugin`` (each worker under its nanny,
  forked from one forkserver that has imported the task modules), then the command with
  ``--dask-address``; the cluster is stopped (SIGTERM) right after the command ends.

CPU seconds are those of the whole process tree (user + system): this process makes itself
the subreaper of its descendants (``prctl(PR_SET_CHILD_SUBREAPER)``), so a forkserver's
workers, a nanny's worker and anything orphaned are reaped here and their CPU lands in
``RUSAGE_CHILDREN``. For Dask that includes the cluster's start-up and its idle time while
the command starts (the forkserver's imports included); ``dask_idle`` measures that part
alone (a cluster started, left idle, stopped, ``IDLE_S`` seconds in all). The scheduler
runs with ``QUIET_SCHEDULER``, the workers with ``WORKER_OPTIONS`` (the settings
docs/speed.md gives for a study cluster). The results CSV of every run is compared with
the first's, byte for byte.

A Dask row also has the CPU of a cluster that was already running: the command's process
tree plus the cluster's processes (``scheduler``, ``nanny``, ``workers``, read with psutil)
while the command ran, without the cluster's start, stop and idle time before (so without
the forkserver's imports, which a running cluster has paid when it started).

Run: .venv/bin/python bench/bench_dask.py  (writes bench/results/bench_dask.json)
or   .venv/bin/python bench/bench_dask.py --example  (the example season sweep itself, 5
replicas, every season's training run, 2 workers: bench/results/bench_dask_example.json)
or   .venv/bin/python bench/bench_dask.py --compare OLD_CHECKOUT  (1 worker, the code of
OLD_CHECKOUT, e.g. a ``git archive`` of main, then this checkout's, back to back: writes
bench/results/bench_dask_compare.json)

Keys of a ``sweep`` row: ``executor`` (local or dask), ``workers``, ``cpu_s`` (process tree,
cluster included), ``command_wall_s`` (the sweep command), ``total_wall_s`` (with the
cluster's start and stop), ``cluster_start_wall_s``, ``load_before``/``load_after``,
``results_sha256`` (of results.csv). ``dask_idle``: ``cpu_s`` over ``wall_s``, and
``cores_busy`` = their ratio. A Dask row: ``running_cluster_cpu_s``, ``command_cpu_s``,
``scheduler_cpu_s``, ``nanny_cpu_s``, ``workers_cpu_s``, and ``over_local`` /
``running_over_local``: its ``cpu_s`` / ``running_cluster_cpu_s`` over the local row's
``cpu_s`` for as many workers. ``summary``: the same ratios per worker count
(``dask_over_local_cpu_N``, ``running_dask_over_local_cpu_N``) against ``goal_ratio``.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import resource
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench_sweep import STUDY, bench_study

from results import record

BIN = Path(sys.executable).parent
#: Worker counts measured.
WORKERS = (1, 2)
#: Seconds to wait for a started cluster to accept its workers.
CLUSTER_START_S = 120.0
PR_SET_CHILD_SUBREAPER = 36
#: The scheduler's settings for a study cluster (docs/speed.md): its event-loop tick and
#: system monitor less often (the workers and nannies are quieted by the study's preload
#: and plugins, ``dask_plugin.QUIET``).
QUIET_SCHEDULER = {"DASK_DISTRIBUTED__ADMIN__TICK__INTERVAL": "1s",
                   "DASK_DISTRIBUTED__ADMIN__SYSTEM_MONITOR__INTERVAL": "5s"}
#: ``dask worker``'s options for a study cluster (docs/speed.md): one thread per worker, no
#: dashboard, no memory monitor, and the study's nanny preload (``dask_plugin.dask_setup``:
#: the workers forked from one process that has imported the task modules, and quiet).
WORKER_OPTIONS = ("--nthreads", "1", "--no-dashboard", "--memory-limit", "0",
                  "--preload-nanny", "spindlebench.studies.running.dask_plugin")
#: Wall seconds of the idle-cluster rows.
IDLE_S = 60.0


def subreaper() -> None:
    """Orphaned descendants are re-parented to this process (Linux), so their CPU counts."""
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) != 0:
        raise SystemExit(f"prctl(PR_SET_CHILD_SUBREAPER): errno {ctypes.get_errno()}")


def reap(keep: tuple[int, ...] = ()) -> None:
    """Wait until every child but ``keep`` has ended, and collect them (re-parented orphans
    included).

    Waiting matters: a local pool's forkserver outlives the sweep command by a moment (it
    exits when it sees the command gone, then is re-parented here), and its CPU, the pool's
    workers' included, counts only once it is collected. Collecting only what had ended when
    the command returned moved a local run's worker CPU into the next row (a Dask row read
    about 3 CPU-s too high, the local row as much too low)."""
    import psutil

    deadline = time.monotonic() + CLUSTER_START_S
    while True:
        try:
            pid, _ = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid:
            continue
        alive = {child.pid for child in psutil.Process().children()} - set(keep)
        if not alive:
            return
        if time.monotonic() > deadline:
            raise SystemExit(f"processes {sorted(alive)} outlived the sweep command")
        time.sleep(0.02)


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


class Cluster:
    """``dask scheduler`` and ``dask worker`` processes of our own, on 127.0.0.1."""

    def __init__(self, workers: int, env: dict | None = None) -> None:
        self.address = f"tcp://127.0.0.1:{free_port()}"
        port = self.address.rsplit(":", 1)[1]
        quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
        self.processes = [subprocess.Popen(
            [str(BIN / "dask"), "scheduler", "--host", "127.0.0.1", "--port", port,
             "--no-dashboard"], env={**(env or os.environ), **QUIET_SCHEDULER}, **quiet)]
        self.processes.append(subprocess.Popen(
            [str(BIN / "dask"), "worker", self.address, "--nworkers", str(workers),
             *WORKER_OPTIONS], env=env, **quiet))
        self._wait_for(workers)

    def _wait_for(self, workers: int) -> None:
        from distributed import Client

        deadline = time.monotonic() + CLUSTER_START_S
        while time.monotonic() < deadline:
            try:
                with Client(self.address, timeout="5s") as client:
                    client.wait_for_workers(workers, timeout=CLUSTER_START_S)
                    return
            except OSError:
                time.sleep(1.0)
        raise SystemExit(f"no Dask cluster with {workers} worker(s) at {self.address}")

    def pids(self) -> tuple[int, ...]:
        return tuple(process.pid for process in self.processes)

    def cpu(self) -> dict[str, float]:
        """CPU seconds so far of the cluster's processes by role: ``scheduler``, ``nanny``
        (the ``dask worker`` process and its nannies) and ``workers`` (the processes the
        nannies spawn)."""
        import psutil

        roles = {"scheduler": 0.0, "nanny": 0.0, "workers": 0.0}
        scheduler, nanny = (psutil.Process(p.pid) for p in self.processes)
        for role, root in (("scheduler", scheduler), ("nanny", nanny)):
            for process in (root, *root.children(recursive=True)):
                try:
                    times = process.cpu_times()
                    spawned = process.pid != root.pid and "-c" in process.cmdline()
                except psutil.Error:
                    continue
                # the workers, the forkserver that forks them (its imports are theirs) and
                # the resource tracker (a few ms): `python -c 'from multiprocessing...'`
                roles["workers" if spawned else role] += times.user + times.system
        return roles

    def stop(self) -> None:
        for process in reversed(self.processes):  # workers first, then the scheduler
            process.send_signal(signal.SIGTERM)
            try:
                process.wait(timeout=60)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        reap()  # nanny-spawned workers exit after their nanny: wait for them


def sweep(study: Path, out: Path, executor: list[str], env: dict | None = None) -> float:
    """Run the sweep command (with ``env``, else this process's environment); its wall
    seconds."""
    start = time.perf_counter()
    subprocess.run([str(BIN / "spindlebench"), "sweep", str(study), "-o", str(out), "-q",
                    *executor], check=True, stdout=subprocess.DEVNULL, env=env)
    return time.perf_counter() - start


def digest(out: Path) -> str:
    return hashlib.sha256((out / "results.csv").read_bytes()).hexdigest()


def measure(study: Path, folder: Path, kind: str, workers: int,
            env: dict | None = None) -> dict:
    out = folder / f"{kind}{workers}"
    reap()
    cpu, load = children_cpu(), list(os.getloadavg())
    start = time.perf_counter()
    if kind == "local":
        wall = sweep(study, out, ["--workers", str(workers)], env)
    else:
        cluster = Cluster(workers, env)
        started = time.perf_counter() - start
        before_cluster, before_command = cluster.cpu(), children_cpu()
        try:
            wall = sweep(study, out, ["--dask-address", cluster.address], env)
            reap(keep=cluster.pids())
            during = {role: cpu_s - before_cluster[role]
                      for role, cpu_s in cluster.cpu().items()}
            command = children_cpu() - before_command
        finally:
            cluster.stop()
    reap()
    row = {"row": "sweep", "executor": kind, "workers": workers,
           "cpu_s": children_cpu() - cpu, "command_wall_s": wall,
           "total_wall_s": time.perf_counter() - start, "load_before": load,
           "load_after": list(os.getloadavg()), "results_sha256": digest(out)}
    if kind == "dask":
        row["cluster_start_wall_s"] = started
        # on a cluster that was already running: the command's process tree and the
        # cluster's processes while the command ran (no start, no stop, no idle before)
        row["running_cluster_cpu_s"] = command + sum(during.values())
        row["command_cpu_s"] = command
        row.update({f"{role}_cpu_s": cpu_s for role, cpu_s in during.items()})
    return row


def idle(workers: int, seconds: float) -> dict:
    """A cluster's own CPU: started, idle for ``seconds``, stopped."""
    reap()
    cpu = children_cpu()
    start = time.perf_counter()
    cluster = Cluster(workers)
    time.sleep(max(0.0, seconds - (time.perf_counter() - start)))
    cluster.stop()
    wall = time.perf_counter() - start
    used = children_cpu() - cpu
    return {"row": "dask_idle", "workers": workers, "cpu_s": used, "wall_s": wall,
            "cores_busy": used / wall}


def compare(before: Path, workers: int = 1) -> None:
    """Back to back, the sweep on the local pool and on Dask with the code of the checkout
    ``before`` (its ``pipeline`` on PYTHONPATH, as for the workers) and with this one's:
    before-local, before-dask, after-local, after-dask (``bench_dask_compare.json``). On a
    shared machine only such back-to-back runs compare."""
    subreaper()
    here = Path(__file__).resolve().parents[1]
    rows: list[dict] = []
    with tempfile.TemporaryDirectory(prefix="bench-dask-compare-") as name:
        folder = Path(name)
        study = bench_study(folder)
        for label, checkout in (("before", before.resolve()), ("after", here)):
            env = {**os.environ, "PYTHONPATH": str(checkout / "pipeline")}
            (folder / label).mkdir()
            for kind in ("local", "dask"):
                row = measure(study, folder / label, kind, workers, env)
                rows.append({**row, "code": label, "checkout": str(checkout)})
                print(f"{label:>6} {kind:>5} {workers} worker(s): {row['cpu_s']:6.1f} CPU-s, "
                      f"command {row['command_wall_s']:5.1f} s wall, load "
                      f"{row['load_before'][0]:.1f} -> {row['load_after'][0]:.1f}", flush=True)
    if len({row["results_sha256"] for row in rows}) != 1:
        raise SystemExit("results.csv differs between runs")
    summary = {}
    for label in ("before", "after"):
        local, dask = (next(r["cpu_s"] for r in rows if r["code"] == label
                            and r["executor"] == kind) for kind in ("local", "dask"))
        running = next(r["running_cluster_cpu_s"] for r in rows if r["code"] == label
                       and r["executor"] == "dask" and "running_cluster_cpu_s" in r)
        summary[f"dask_over_local_cpu_{label}"] = dask / local
        summary[f"running_dask_over_local_cpu_{label}"] = running / local
        print(f"{label}: Dask / local pool CPU = {dask / local:.2f} with the cluster's start "
              f"and stop, {running / local:.2f} on a running cluster (goal <= 1.2)")
    rows.append({"row": "summary", **summary, "goal_ratio": 1.2})
    path = record("bench_dask", rows, {"dask_over_local_cpu": 1.2}, name="bench_dask_compare")
    print(f"wrote {path}")


def main() -> None:
    if sys.argv[1:2] == ["--compare"]:
        compare(Path(sys.argv[2]))
        return
    example = sys.argv[1:2] == ["--example"]
    subreaper()
    print("load average (1, 5, 15 min): " + ", ".join(f"{v:.1f}" for v in os.getloadavg()))
    rows: list[dict] = []
    with tempfile.TemporaryDirectory(prefix="bench-dask-") as name:
        folder = Path(name)
        study = STUDY if example else bench_study(folder)
        for workers in (2,) if example else WORKERS:
            for kind in ("local", "dask"):
                row = measure(study, folder, kind, workers)
                if kind == "dask":
                    row["over_local"] = row["cpu_s"] / rows[-1]["cpu_s"]
                    row["running_over_local"] = row["running_cluster_cpu_s"] / rows[-1]["cpu_s"]
                rows.append(row)
                print(f"{kind:>6} {workers} worker(s): {row['cpu_s']:7.1f} CPU-s, command "
                      f"{row['command_wall_s']:6.1f} s wall, load {row['load_after'][0]:.1f}",
                      flush=True)
            if example:
                continue
            rows.append(idle(workers, IDLE_S))
            print(f"  idle cluster of {workers} for {rows[-1]['wall_s']:.0f} s: "
                  f"{rows[-1]['cpu_s']:.1f} CPU-s", flush=True)
    if len({row["results_sha256"] for row in rows if row["row"] == "sweep"}) != 1:
        raise SystemExit("results.csv differs between executors")
    summary = {}
    for workers in (2,) if example else WORKERS:
        local = next(r for r in rows if r["row"] == "sweep" and r["executor"] == "local"
                     and r["workers"] == workers)
        dask = next(r for r in rows if r["row"] == "sweep" and r["executor"] == "dask"
                    and r["workers"] == workers)
        summary[f"dask_over_local_cpu_{workers}"] = dask["cpu_s"] / local["cpu_s"]
        summary[f"running_dask_over_local_cpu_{workers}"] = (dask["running_cluster_cpu_s"]
                                                             / local["cpu_s"])
        print(f"{workers} worker(s): Dask / local pool CPU = "
              f"{dask['cpu_s'] / local['cpu_s']:.2f} with the cluster's start and stop, "
              f"{dask['running_cluster_cpu_s'] / local['cpu_s']:.2f} on a running cluster "
              "(goal <= 1.2)")
    rows.append({"row": "summary", **summary, "goal_ratio": 1.2})
    name = "bench_dask_example" if example else "bench_dask"
    print(f"wrote {record('bench_dask', rows, {'dask_over_local_cpu': 1.2}, name=name)}")


if __name__ == "__main__":
    main()
