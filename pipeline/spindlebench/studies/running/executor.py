"""Run a study's tasks on local worker processes, in-process, or on a Dask cluster.

Every backend is a ``concurrent.futures.Executor``: a ``ProcessPoolExecutor`` by default, an
in-process executor for ``workers=0`` (debugging, profiling), and for a Dask address the
executor of a ``distributed.Client`` connected to that scheduler, so a study that outgrows
one machine runs on many without a line of study code changing.

:func:`TaskRunner.run` isolates failures: an exception inside a task becomes a failed
:class:`Outcome` carrying its one-line message, and a worker process that dies (a crash in
native FMU code) breaks only the tasks it was running, which are retried one by one in
quarantine so the crash is pinned to the task that caused it. Handlers may answer an
outcome with follow-up tasks (an evaluation once its simulations are in), so the workers
never idle between the phases of a study.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import errno
import functools
import gc
import multiprocessing
import os
import pickle
import re
import select
import socket
import struct
import sys
import threading
import time
import traceback
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

from spindlebench.core import interrupts
from spindlebench.core.console import one_line_error
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.progress import tqdm_class

#: The modules of a study's task functions (``jobs.simulate_job``, ``jobs.evaluate_job``): what
#: the local pool preloads for a study (``TaskRunner._opener`` takes its tasks' modules) and
#: what a study cluster's nannies preload for their workers (``dask_plugin.dask_setup``), which
#: start before any study's tasks are known.
TASK_MODULES = ("spindlebench.studies.running.jobs",)
#: A Dask scheduler address: protocol://host:port (tcp, tls, ucx, ws, wss, inproc).
DASK_ADDRESS = re.compile(r"^(tcp|tls|ucx|wss?)://[^\s/]+:\d+/?$")


@dataclass(frozen=True)
class Task:
    """One unit of work: ``fn(*args)`` under a unique ``key``; ``fn`` must be importable."""

    key: str
    fn: Callable[..., Any]
    args: tuple[Any, ...] = ()
    kind: str = "task"


@dataclass(frozen=True)
class Outcome:
    """What became of a task: its value, or the one-line error and the traceback."""

    task: Task
    value: Any = None
    error: str | None = None
    detail: str = ""
    seconds: float = 0.0
    #: CPU seconds of the process that ran the task, spent inside the task function.
    cpu_s: float = 0.0
    #: CPU seconds of the local worker that ran the task, spent outside any task function
    #: since its previous task ended (``WorkerClock``).
    outside_cpu_s: float = 0.0

    @property
    def ok(self) -> bool:
        return self.error is None


@dataclass
class RunStats:
    """Counts per task kind, for reports, benchmarks and tests."""

    done: dict[str, int] = field(default_factory=dict)
    failed: dict[str, int] = field(default_factory=dict)
    seconds: float = 0.0
    #: Seconds spent inside the task functions, summed over workers, per kind.
    busy_s: dict[str, float] = field(default_factory=dict)
    #: CPU seconds spent inside the task functions, summed over workers, per kind (on a
    #: shared machine the wall seconds above also hold other programs' time).
    cpu_s: dict[str, float] = field(default_factory=dict)
    #: CPU seconds of the local worker processes outside the task functions: their start-up
    #: (imports), unpickling each task's arguments, pickling each result but a worker's
    #: last; and of the forkserver that forks them (the imports it preloads for them). Not
    #: in ``cpu_s`` and not in the study process's own CPU, yet spent for the study (0
    #: in-process, where that process's CPU holds it, and on Dask).
    outside_cpu_s: float = 0.0

    def count(self, outcome: Outcome) -> None:
        kind = outcome.task.kind
        bucket = self.done if outcome.ok else self.failed
        bucket[kind] = bucket.get(kind, 0) + 1
        self.busy_s[kind] = self.busy_s.get(kind, 0.0) + outcome.seconds
        self.cpu_s[kind] = self.cpu_s.get(kind, 0.0) + outcome.cpu_s
        self.outside_cpu_s += outcome.outside_cpu_s

    def total(self, kind: str | None = None) -> int:
        if kind is None:
            return sum(self.done.values()) + sum(self.failed.values())
        return self.done.get(kind, 0) + self.failed.get(kind, 0)


class WorkerClock:
    """A local worker's CPU seconds counted so far, in or outside its tasks.

    The pool unpickles a task's arguments before ``call_isolated`` starts its clock and
    pickles the result after it stops it: in a worker, the CPU spent between two tasks (and
    before the first: the imports) is the worker's outside a task function, reported with
    the next task so that a study's CPU can be counted whole. ``counted`` is None outside a
    local worker: in-process that CPU is the study process's own, already counted there."""

    counted: float | None = None

    @classmethod
    def start(cls) -> None:
        """In a fresh worker: everything the process spent so far is still to report."""
        cls.counted = 0.0

    @classmethod
    def outside(cls, now: float) -> float:
        """CPU seconds since the last count (0 outside a local worker)."""
        return 0.0 if cls.counted is None else now - cls.counted

    @classmethod
    def count_to(cls, now: float) -> None:
        if cls.counted is not None:
            cls.counted = now


def call_isolated(fn: Callable[..., Any], args: tuple[Any, ...]) -> tuple[Any, str | None, str,
                                                                          float, float, float]:
    """Run ``fn(*args)`` in a worker; an exception comes back as data, never as a raise.
    Returns (value, error, traceback, wall seconds, CPU seconds, CPU seconds of this worker
    outside any task since its last one: ``WorkerClock``)."""
    start, cpu = time.perf_counter(), time.process_time()
    outside = WorkerClock.outside(cpu)
    try:
        value, error, detail = fn(*args), None, ""
    except Exception as exc:  # failure isolation: every error becomes a recorded outcome
        value, error, detail = None, one_line_error(exc), traceback.format_exc()
    end = time.process_time()
    WorkerClock.count_to(end)
    return value, error, detail, time.perf_counter() - start, end - cpu, outside


class InlineExecutor(cf.Executor):
    """Runs each task at submission, in this process: no pickling, easy to debug."""

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> cf.Future[Any]:
        future: cf.Future[Any] = cf.Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as exc:
            future.set_exception(exc)
        return future


def default_workers() -> int:
    return max(1, os.cpu_count() or 1)


def single_threaded_worker(parent_pid: int | None = None) -> None:
    """Worker initializer: one BLAS thread per process, one-line warnings, and exit when the
    study process dies.

    The workers already fill the cores; a multi-threaded BLAS in each of them oversubscribes
    the machine, and OpenBLAS's spinning threads then make two workers slower than one.
    A worker is a child of the forkserver, not of the study process, and waits on its task
    queue forever: after a ``kill -9`` of the study it would live on, reparented to PID 1
    (and keep the forkserver and resource tracker alive with it), so it watches
    ``parent_pid`` and exits as soon as that process is gone.
    """
    import warnings

    from threadpoolctl import threadpool_limits

    from spindlebench.core.console import print_warning

    WorkerClock.start()
    threadpool_limits(limits=1)
    warnings.showwarning = print_warning  # one line, as in the study process, no source line
    if parent_pid is not None:
        threading.Thread(target=_exit_with, args=(parent_pid,), daemon=True,
                         name="exit-with-parent").start()


def _exit_with(pid: int) -> None:
    """Block until process ``pid`` ends, then end this process at once."""
    try:
        handle = os.pidfd_open(pid)  # readable when the process ends (Linux >= 5.3)
    except (AttributeError, OSError):
        handle = None
    if handle is not None:
        select.select([handle], [], [])
    else:
        while _alive(pid):
            time.sleep(1.0)
    os._exit(1)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _local_pool(workers: int, preload: Iterable[str] = ()) -> cf.ProcessPoolExecutor:
    """A pool of ``workers`` processes forked from this process's forkserver.

    ``preload``: modules the forkserver imports when it starts (later calls cannot change
    what a running one holds), so that every worker is forked with them instead of
    importing them itself: the task modules of a sweep (NumPy, SciPy, pandas, scikit-learn,
    FMPy) cost each worker 2.3 CPU-s of imports. (``__main__`` stays first, as in the
    default; Python 3.11's forkserver ignores it.)"""
    # forkserver: forking a process that runs threads (tqdm, Dask) can deadlock the child.
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["__main__", *preload])
    return cf.ProcessPoolExecutor(max_workers=workers, mp_context=context,
                                  initializer=single_threaded_worker, initargs=(os.getpid(),))


def _stop_workers(executor: cf.Executor) -> None:
    """End a local pool's workers now (Ctrl-C: do not wait for their running simulations).

    SIGKILL, not SIGTERM: a worker inside a simulation defers SIGTERM
    (``interrupts.deferred``), ends only that task and lives on, while one that was idle dies
    at once, possibly holding the pool's task-queue lock; the survivor then waits on that lock
    forever and the pool's shutdown with it (a study hung at exit). Workers hold nothing to
    save: results are written by this process, and the unpacked FMU folder of a killed worker
    is removed by the next process that unpacks (``runner.extracted_fmu``)."""
    _kill(list((getattr(executor, "_processes", None) or {}).values()))


def _kill(processes: list[Any]) -> None:
    for process in processes:
        if process.exitcode is None:
            process.kill()


#: Longest first message a Dask scheduler sends (its handshake is a few hundred bytes).
MAX_HANDSHAKE_BYTES = 1 << 20
_TCP_ADDRESS = re.compile(r"^tcp://(\[[^\]]+\]|[^\s/:]+):(\d+)/?$")


def check_dask_scheduler(address: str, timeout_s: float) -> None:
    """Refuse, in one line, a ``tcp://`` address where no Dask scheduler answers.

    A Dask scheduler writes its handshake first: an 8-byte length, then a short msgpack
    message naming its compression and pickle protocol. Something else on the port (a web
    server's reply read as that length) made the client try to allocate 3 EiB; a port that
    accepts and says nothing made it wait. So the first message is read here, with a
    timeout, and must be short and look like a handshake. Other protocols (tls, ucx, ...)
    are left to the client's own timeout."""
    match = _TCP_ADDRESS.match(address)
    if match is None:
        return
    host, port = match.group(1).strip("[]"), int(match.group(2))
    where = f"--dask-address {address}"
    try:
        with socket.create_connection((host, port), timeout=timeout_s) as sock:
            sock.settimeout(timeout_s)
            size = struct.unpack("<Q", _receive(sock, 8))[0]
            if not 0 < size <= MAX_HANDSHAKE_BYTES:
                raise SpindlebenchError(f"{where}: not a Dask scheduler (its first message "
                                        f"claims {size:,} bytes, a handshake has a few "
                                        "hundred)")
            body = _receive(sock, size)
    except TimeoutError:
        raise SpindlebenchError(f"{where}: no Dask handshake within {timeout_s:g} s (is a Dask "
                                "scheduler listening there?)") from None
    except OSError as exc:
        raise SpindlebenchError(f"{where}: cannot connect to a Dask scheduler "
                                f"({exc.strerror or exc})") from None
    if b"pickle-protocol" not in body or b"compression" not in body:
        raise SpindlebenchError(f"{where}: not a Dask scheduler (its first message is not a "
                                "Dask handshake)")


def _receive(sock: socket.socket, size: int) -> bytes:
    chunks, left = [], size
    while left:
        chunk = sock.recv(min(left, 1 << 16))
        if not chunk:
            raise ConnectionError(errno.ECONNRESET, "closed before its handshake")
        chunks.append(chunk)
        left -= len(chunk)
    return b"".join(chunks)


@contextmanager
def dask_executor(address: str, timeout_s: float = 10.0) -> Iterator[cf.Executor]:
    """The executor of a Dask client connected to the scheduler at ``address`` (checked to
    be one first, :func:`check_dask_scheduler`)."""
    try:
        import distributed
    except ImportError:  # pragma: no cover - distributed is a pinned requirement
        raise SpindlebenchError("--dask-address needs the 'distributed' package") from None
    check_dask_scheduler(address, timeout_s)
    try:
        # direct_to_workers: results (a 6 h recording is a few MB) come from the worker that
        # holds them, not relayed through the scheduler, the one part N machines share
        client = distributed.Client(address, timeout=f"{timeout_s}s", set_as_default=False,
                                    direct_to_workers=True)
    except Exception as exc:  # OSError, TimeoutError, a non-Dask peer's protocol error ...
        _discard_half_made_clients(exc, distributed.Client)
        raise SpindlebenchError(
            f"--dask-address {address}: cannot connect to a Dask scheduler ({one_line_error(exc)})"
        ) from None
    try:
        # every worker, also one that joins later, single-threaded in BLAS like the local pool
        from spindlebench.studies.running.dask_plugin import OneBlasThread, QuietNanny

        client.register_plugin(OneBlasThread(), name=OneBlasThread.name)
        client.register_plugin(QuietNanny(), name=QuietNanny.name)
        # pure=False: each task's key a fresh id. The default (pure) hashes every argument
        # to make the key, a whole evaluation job's truths included, in this process for
        # each task, to share results between identical calls that a study never makes
        # (and a task rerun after a lost worker must not get the first call's key back).
        yield SealedExecutor(client.get_executor(pure=False))
    finally:
        client.close()


class SealedCall:
    """``fn(*args)`` that pickles as the call itself, so that unpickling it runs it, and
    whose value comes back sealed too (:func:`sealed_value`).

    The scheduler unpickles every task it is given (to find the task's dependencies): a study
    task handed to it as ``fn, args`` made it import the study's modules (SciPy,
    scikit-learn, pandas: about 2 CPU-s in a 48-simulation sweep, and spindlebench installed
    on the scheduler's machine) and rebuild each evaluation job's truths, only to pickle them
    again for the worker. Sealed, a task is ``pickle.loads(BYTES)``: the scheduler sees a
    standard-library function and one bytes object, and only the worker unpickles, imports
    and runs the call."""

    def __init__(self, fn: Callable[..., Any], args: tuple[Any, ...]) -> None:
        self.fn, self.args = fn, args

    def __reduce__(self) -> tuple[Callable[..., Any], tuple[Any, ...]]:
        return sealed_value, (self.fn, self.args)

    def seal(self) -> bytes:
        """The call as bytes, by cloudpickle as Dask pickles a task (a function defined in a
        test or a notebook is pickled by value); ``pickle.loads`` reads them."""
        import cloudpickle  # a requirement of dask

        return cloudpickle.dumps(self, protocol=pickle.HIGHEST_PROTOCOL)


def sealed_value(fn: Callable[..., Any], args: tuple[Any, ...]) -> bytes:
    """``fn(*args)``'s value, pickled: what a sealed call gives its Dask worker.

    The worker keeps a task's value until the client has it, and measures it first (Dask's
    ``sizeof``) in its event loop: for a recording's frame that walks every column, about 7
    CPU-ms, where pickling the frame takes 0.2; as bytes, the value is measured at once and
    sent as it is, and the client unpickles it (``SealedExecutor``), as the local pool's
    study process unpickles its workers' values."""
    return pickle.dumps(fn(*args), protocol=pickle.HIGHEST_PROTOCOL)


class SealedExecutor(cf.Executor):
    """A Dask client's executor whose tasks are sealed (:class:`SealedCall`): its futures
    give the tasks' values unpickled."""

    def __init__(self, executor: cf.Executor) -> None:
        self.executor = executor

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> cf.Future[Any]:
        if kwargs:
            raise TypeError("a sealed task takes positional arguments only")
        return _unsealed(self.executor.submit(pickle.loads, SealedCall(fn, args).seal()))

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        self.executor.shutdown(wait=wait, cancel_futures=cancel_futures)


def _unsealed(sealed: cf.Future[bytes]) -> cf.Future[Any]:
    """A future of ``pickle.loads`` of ``sealed``'s bytes (its exception or cancellation as
    they are). Cancelling it cancels ``sealed`` too, which a Dask client's executor passes
    on to the scheduler (``distributed.cfexecutor``): the task is dropped, not run for
    nobody."""
    future: cf.Future[Any] = cf.Future()

    def cancelled(future: cf.Future[Any]) -> None:
        if future.cancelled():
            sealed.cancel()

    future.add_done_callback(cancelled)

    def done(sealed: cf.Future[bytes]) -> None:
        if sealed.cancelled():
            future.cancel()
            return
        if future.cancelled():  # cancelled here while it ran: nobody waits for its value
            return
        try:
            future.set_result(pickle.loads(sealed.result()))
        except BaseException as exc:  # the task's, or its value's unpickling
            future.set_exception(exc)

    sealed.add_done_callback(done)
    return future


def _discard_half_made_clients(exc: BaseException, client_type: type) -> None:
    """Mark the client whose constructor raised ``exc`` as closed: its ``__del__`` otherwise
    tries to close a connection that never opened, waits twice the timeout and prints a
    traceback at exit ("Exception ignored in Client.__del__ ... TimeoutError", seen with a
    ``tls://`` address and no TLS configuration) after the one-line error."""
    trace = exc.__traceback__
    while trace is not None:
        client = trace.tb_frame.f_locals.get("self")
        if isinstance(client, client_type):
            with contextlib.suppress(Exception):
                client.close(timeout=1)
            client.status = "closed"
        trace = trace.tb_next


#: The variables that fix the BLAS/OpenMP libraries' thread counts (read when they load).
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def one_blas_thread() -> dict[str, Any]:
    """Make this process single-threaded in BLAS (as ``single_threaded_worker`` does for the
    local pool): the variables for libraries loaded later and for child processes, and
    ``threadpoolctl`` for those already loaded (a Dask worker has NumPy loaded before any
    task). Returns what ``threadpoolctl`` then reports, one dict per library."""
    from threadpoolctl import threadpool_info, threadpool_limits

    for variable in BLAS_THREAD_VARIABLES:
        os.environ[variable] = "1"
    threadpool_limits(limits=1)
    return {"variables": {v: os.environ[v] for v in BLAS_THREAD_VARIABLES},
            "libraries": [{"api": i.get("user_api"), "num_threads": i.get("num_threads")}
                          for i in threadpool_info()]}


@functools.cache
def freeze_start_up() -> None:
    """Leave this process's objects so far (its modules, the study) out of the cyclic
    garbage collector's scans from now on; once per process, at its first run (a later
    run's objects, a test session's, are collected as usual).

    They are some 140 000 objects that live as long as the process, and a full collection
    scans them all: 0.1 CPU-s each, 6 of them in a 12-replica season sweep's study process
    (0.30-0.35 of its 0.41-0.46 CPU-s in the collector, 3 runs); frozen, the collector took
    0.17-0.21 CPU-s (gc.callbacks, 5 runs). Not done in the workers: measured, a simulation
    triggers no full collection and an evaluation job 0.5 ms of collections (0.4 %).
    Without a ``gc.collect()`` first (a full collection itself): at most the few hundred
    unreachable objects in the young generations are kept frozen with them."""
    gc.freeze()


def _refuse_an_unguarded_main() -> None:
    """Stop, in one line, a run with local workers that each worker would start again
    (``main_guard``): in the script, before anything starts; in a worker importing it (where
    the script's source could not be read), with the same line and no traceback."""
    from spindlebench.studies.running import main_guard

    if main_guard.importing_main_in_a_worker():
        print(f"error: {main_guard.guard_message(sys.argv[0] or 'the main script')}",
              file=sys.stderr, flush=True)
        raise SystemExit(1)
    unguarded = main_guard.unguarded_main_line()
    if unguarded is not None:
        raise SpindlebenchError(main_guard.guard_message(*unguarded))


class TaskRunner:
    """Runs tasks with failure isolation, follow-up tasks and a done/total progress bar."""

    def __init__(self, workers: int | None = None, dask_address: str | None = None,
                 progress: bool = True, desc: str = "tasks", unit: str = "task",
                 connect_timeout_s: float = 10.0) -> None:
        if workers is not None and workers < 0:
            raise SpindlebenchError(f"--workers must be >= 0, got {workers}")
        self.workers = default_workers() if workers is None else workers
        if self.workers and not dask_address:
            _refuse_an_unguarded_main()
        if dask_address is not None and dask_address.startswith("inproc://"):
            raise SpindlebenchError(f"--dask-address {dask_address!r}: an in-process address "
                                    "names a scheduler inside this very process, and there is "
                                    "none; give a running cluster's tcp://HOST:PORT")
        if dask_address is not None and not DASK_ADDRESS.match(dask_address):
            raise SpindlebenchError(f"--dask-address {dask_address!r}: expected a scheduler "
                                    "address like tcp://HOST:PORT")
        self.dask_address = dask_address
        self.progress = progress
        self.desc = desc
        self.unit = unit
        self.connect_timeout_s = connect_timeout_s
        self._dask: cf.Executor | None = None

    @contextmanager
    def connected(self) -> Iterator[TaskRunner]:
        """Connect to the Dask scheduler now (if any) and keep the connection for ``run``.

        Entered before a study touches its results folder, so an unreachable scheduler is
        one line with nothing written, not a folder with a state.json and no results.
        """
        if not self.dask_address or self._dask is not None:
            yield self
            return
        with dask_executor(self.dask_address, self.connect_timeout_s) as executor:
            self._dask = executor
            try:
                yield self
            finally:
                self._dask = None

    def describe(self) -> str:
        if self.dask_address:
            return f"Dask cluster at {self.dask_address}"
        if self.workers == 0:
            return "in-process"
        return f"{self.workers} local worker process(es)"

    def _max_in_flight(self) -> int:
        """Tasks handed to the executor at once: enough to keep every worker busy, few
        enough that follow-ups start early and results stream to disk in order."""
        if self.dask_address:
            return 1 << 30  # the scheduler balances its workers itself
        return max(1, 2 * self.workers)

    def _opener(self, tasks: list[Task]) -> Callable[[], cf.Executor]:
        """Opens the executor for ``tasks``: a local pool preloads their functions' modules
        (follow-ups are usually of the same modules: a sweep's both kinds are in one)."""
        if self.workers == 0:
            return InlineExecutor
        preload = sorted({task.fn.__module__ for task in tasks})
        return lambda: _local_pool(self.workers, preload)

    def run(self, tasks: Iterable[Task],
            on_outcome: Callable[[Outcome], Iterable[Task] | None] | None = None,
            expected_follow_ups: int = 0) -> RunStats:
        """Run ``tasks`` (and any follow-ups ``on_outcome`` returns) to completion.

        ``on_outcome`` runs in this process, in completion order; it is where results are
        written to disk, so a sweep interrupted at any moment keeps every finished task.
        ``expected_follow_ups`` lets the progress bar show the true total from the start.
        """
        stats = RunStats()
        start = time.perf_counter()
        freeze_start_up()
        queue = list(tasks)
        bar = tqdm_class()(total=len(queue) + expected_follow_ups, desc=self.desc, unit=self.unit,
                   disable=not self.progress, dynamic_ncols=True, smoothing=0.1)
        try:
            if self.dask_address:
                with self.connected():
                    executor = self._dask
                    self._drain(lambda: executor, queue, on_outcome, stats, bar)
            else:
                forkserver_cpu = _forkserver_cpu_s()
                try:
                    self._drain(self._opener(queue), queue, on_outcome, stats, bar)
                finally:  # the workers' imports are the forkserver's now (_local_pool)
                    stats.outside_cpu_s += _forkserver_cpu_s() - forkserver_cpu
        finally:
            bar.close()
            stats.seconds = time.perf_counter() - start
        return stats

    def _drain(self, open_executor: Callable[[], cf.Executor], queue: list[Task],
               on_outcome: Callable[[Outcome], Iterable[Task] | None] | None,
               stats: RunStats, bar: Any) -> None:
        """Submit, collect and hand over outcomes until no task is left.

        When a local worker dies the pool is unusable: the tasks it was running are rerun
        one by one in quarantine (each in a fresh one-worker pool) so the crash is pinned on
        the task that causes it, then a fresh pool takes the rest.
        """

        known = len(queue)  # tasks seen so far, follow-ups included

        def finish(outcome: Outcome) -> None:
            nonlocal known
            stats.count(outcome)
            follow_ups = list(on_outcome(outcome) or ()) if on_outcome else []
            queue.extend(follow_ups)
            known += len(follow_ups)
            bar.total = max(bar.total, known)
            done = ", ".join(f"{kind} {count}" for kind, count in stats.done.items())
            failed = sum(stats.failed.values())
            bar.set_postfix_str(done + (f", failed {failed}" if failed else ""), refresh=False)
            bar.update(1)

        while queue:
            executor = open_executor()
            running: dict[cf.Future[Any], Task] = {}
            victims: list[Task] = []
            local = not isinstance(executor, InlineExecutor) and not self.dask_address
            broken = False
            try:
                while queue or running:
                    while queue and not victims and len(running) < self._max_in_flight():
                        task = queue.pop(0)
                        try:
                            future = executor.submit(call_isolated, task.fn, task.args)
                        except BrokenProcessPool:
                            victims.append(task)
                            break
                        running[future] = task
                    if not running:
                        break
                    done, _ = cf.wait(running, timeout=WATCH_S if local else None,
                                      return_when=cf.FIRST_COMPLETED)
                    if not done and local and _dead_worker(executor):
                        # a worker killed from outside (the out-of-memory killer): the pool
                        # may never say so, so its tasks are victims now
                        broken = True
                        victims.extend(running.values())
                        running.clear()
                        break
                    for future in done:
                        task = running.pop(future)
                        try:
                            value, error, detail, seconds, cpu_s, outside = future.result()
                        except BrokenProcessPool:
                            broken = True
                            victims.append(task)
                            continue
                        except Exception as exc:  # a Dask worker lost, an unpicklable result
                            finish(Outcome(task, error=one_line_error(exc), detail=repr(exc)))
                            continue
                        finish(Outcome(task, value, error, detail, seconds, cpu_s, outside))
            except KeyboardInterrupt:  # Ctrl-C or SIGTERM: stop now, keep what is written
                broken = True
                raise
            finally:
                if local:
                    with interrupts.deferred():  # a second signal must not cut the stop short
                        _close_pool(executor, kill=broken or bool(victims))
            for task in victims:
                finish(_run_quarantined(task))


def _forkserver_cpu_s() -> float:
    """CPU seconds this process's forkserver has spent (imports, forking workers); 0 when
    none runs."""
    from multiprocessing import forkserver

    import psutil

    pid = getattr(forkserver._forkserver, "_forkserver_pid", None)
    if pid is None:
        return 0.0
    try:
        times = psutil.Process(pid).cpu_times()
    except psutil.Error:
        return 0.0
    return times.user + times.system


#: Seconds between two looks at the local workers while waiting for a result.
WATCH_S = 0.5
#: Longest wait for a local pool to shut down once its workers are stopped.
SHUTDOWN_TIMEOUT_S = 30.0
#: How long a pool whose workers were killed may take to notice before it is unblocked.
UNBLOCK_AFTER_S = 1.0


def _dead_worker(executor: cf.Executor) -> bool:
    """Whether a worker process of a local pool has ended (a pool's workers live as long as
    the pool: one that ended was killed or crashed)."""
    processes = getattr(executor, "_processes", None) or {}
    return any(process.exitcode is not None for process in list(processes.values()))


def _close_pool(executor: cf.Executor, kill: bool) -> None:
    """Shut a local pool down without ever waiting forever.

    ``kill``: after a dead worker or a signal, every worker is stopped first: one killed
    while sending its result leaves half a message in the result pipe, and the pool's
    manager thread then waits in ``recv`` for the rest for ever; it never looks at its
    workers again, so the pool never breaks and ``shutdown(wait=True)`` (with Ctrl-C
    deferred) waited with it: a sweep only ``kill -9`` ended. So the manager gets a moment,
    then is unblocked (:func:`_unblock`) and joined with a timeout."""
    # what shutdown() drops its references to
    processes = list((getattr(executor, "_processes", None) or {}).values())
    manager = getattr(executor, "_executor_manager_thread", None)
    queues = (getattr(executor, "_call_queue", None), getattr(executor, "_result_queue", None))
    if kill:
        _kill(processes)
    executor.shutdown(wait=False, cancel_futures=True)
    if manager is None:
        return
    manager.join(UNBLOCK_AFTER_S if kill else SHUTDOWN_TIMEOUT_S)
    if manager.is_alive():
        _kill(processes)
        _unblock(*queues, manager)
        manager.join(SHUTDOWN_TIMEOUT_S)


def _unblock(calls: Any, results: Any, manager: threading.Thread) -> None:
    """Free a pool's manager thread stuck on pipes of dead workers.

    The result pipe: it waits for the rest of a message a killed worker never finished, so
    bytes are written until that message is complete (its unpickling then fails and the
    thread ends the pool as broken). The task pipe: a feeder thread writing a task to a dead
    worker blocks; closing this process's reading end makes its write fail (Python 3.12's
    pool does the same)."""
    with contextlib.suppress(Exception):
        calls._reader.close()
    writer = getattr(results, "_writer", None)
    if writer is None:
        return
    try:
        fd = writer.fileno()
        os.set_blocking(fd, False)
    except (OSError, ValueError):
        return
    block = bytes(1 << 20)
    deadline = time.monotonic() + SHUTDOWN_TIMEOUT_S
    while manager.is_alive() and time.monotonic() < deadline:
        try:
            os.write(fd, block)
        except BlockingIOError:
            manager.join(0.01)  # the pipe is full: let the manager read
        except OSError:
            return


def _run_quarantined(task: Task) -> Outcome:
    """Rerun ``task`` alone in a fresh one-worker pool: a crash is then its own, reported
    on it; a worker killed from outside is retried here and the task succeeds."""
    pool = _local_pool(1)
    future = pool.submit(call_isolated, task.fn, task.args)
    died = Outcome(task, error="worker process died while running this task (killed, out of "
                               "memory, or a crash in native code, e.g. the FMU?)")
    try:
        while True:
            try:
                value, error, detail, seconds, cpu_s, outside = future.result(timeout=WATCH_S)
                break
            except cf.TimeoutError:
                if _dead_worker(pool):
                    return died
            except BrokenProcessPool:
                return died
    finally:
        with interrupts.deferred():
            _close_pool(pool, kill=not future.done() or future.exception() is not None)
    return Outcome(task, value, error, detail, seconds, cpu_s, outside)
