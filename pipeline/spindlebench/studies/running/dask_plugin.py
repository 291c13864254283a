"""The Dask side of a study: the plugins its client registers (every worker single-threaded
in BLAS, every worker and nanny quiet) and the nanny preload a study cluster is started with
(``dask_setup``: workers forked from one parent that has imported the study's task modules).

Its own module because it subclasses ``distributed``'s ``WorkerPlugin`` (Dask refuses
duck-typed plugins), and importing ``distributed`` costs about a CPU-second that a local
study must not pay: ``executor.dask_executor`` imports this module only when it connects to a
cluster. The workers unpickle the plugins by reference, so they import it from the installed
package, as they import the study's tasks.
"""

from __future__ import annotations

import multiprocessing
from typing import Any

import dask.config
import distributed.utils
from distributed.diagnostics.plugin import NannyPlugin, WorkerPlugin
from distributed.nanny import Nanny

from spindlebench.studies.running.executor import TASK_MODULES, one_blas_thread

#: A Dask server's periodic work that a study does not need, and its new period in ms (None:
#: stopped). With the defaults an idle worker, its nanny and the scheduler wake up every 10 to
#: 20 ms (the statistical profiler, the event-loop health "tick") and sample the system every
#: 500 ms: on this machine an idle 1-worker cluster burnt about a tenth of a core, which on a
#: sweep of a few minutes' wall time doubled the CPU of the local pool. The profiler only
#: feeds the dashboard's profile page; the tick only logs a blocked event loop; the system
#: monitor feeds the dashboard and the heartbeats' metrics (kept, less often).
QUIET = {"profile": None, "profile-cycle": None, "tick": 1000, "monitor": 5000}
#: What a study cluster's forkserver imports before it forks the workers (``dask_setup``):
#: the dask command (``__main__``, which a worker re-runs at its start otherwise),
#: ``distributed`` (with Dask, msgpack, cloudpickle, tornado and toolz: distributed's own
#: list but NumPy and pandas, which the task modules import), this module (each worker's
#: preload) and the study's task modules.
FORKSERVER_PRELOAD = ("__main__", "distributed", __name__, *TASK_MODULES)


def quiet(server: Any) -> None:
    """Apply ``QUIET`` to a worker's or nanny's periodic callbacks (those it has). A stopped
    one is also taken out of its list: a server that has not finished starting (a preload's
    ``dask_setup``) starts every callback of the list afterwards."""
    for name, period_ms in QUIET.items():
        if period_ms is None:
            callback = server.periodic_callbacks.pop(name, None)
            if callback is not None:
                callback.stop()
        elif name in server.periodic_callbacks:
            server.periodic_callbacks[name].callback_time = period_ms


class OneBlasThread(WorkerPlugin):
    """``executor.one_blas_thread`` in every worker when it starts, or at once in the workers
    already running when the plugin is registered. A worker runs ``nthreads`` tasks at a time;
    a multi-threaded BLAS under each oversubscribes the cores as in the local pool, where two
    OpenBLAS thread pools spinning against each other made 2 workers slower than 1."""

    name = "spindlebench-one-blas-thread"

    def setup(self, worker: Any) -> None:
        one_blas_thread()
        quiet(worker)


class QuietNanny(NannyPlugin):
    """``quiet`` in every nanny (a nanny plugin runs in the nanny process, which watches its
    worker and restarts it if it dies): its tick and system monitor, as in the worker."""

    name = "spindlebench-quiet-nanny"

    def setup(self, nanny: Any) -> None:
        quiet(nanny)


def dask_setup(server: Any) -> None:
    """A study cluster's nanny preload: ``dask worker ADDRESS --nthreads 1
    --preload-nanny spindlebench.studies.running.dask_plugin`` (docs/speed.md), run by each
    nanny before it starts its worker, and by each worker as its own preload.

    In a nanny: its workers are forked from a forkserver that has imported Dask and the
    study's task modules once (``FORKSERVER_PRELOAD``, as the local pool's forkserver does),
    instead of each worker, spawned by Dask's default, importing them itself (about 3 CPU-s
    a worker, most of what a Dask worker cost over a local one; a restarted worker comes from
    the same forkserver); the forkserver, and so every worker, starts with
    ``one_blas_thread``'s variables set; the nanny is quiet (``quiet``) from the start, and
    so is each worker, which runs this module as its own preload (the client's plugins do it
    again when a study connects, for clusters started otherwise)."""
    quiet(server)
    one_blas_thread()  # in a nanny: before the forkserver starts, which inherits them
    if not isinstance(server, Nanny):
        return
    dask.config.set({"distributed.worker.multiprocessing-method": "forkserver"})
    multiprocessing.get_context("forkserver").set_forkserver_preload(list(FORKSERVER_PRELOAD))
    # distributed's get_mp_context would replace that list with its own (distributed and its
    # packages, each imported here first to see whether it is installed: NumPy and pandas in
    # the nanny, about 0.3 CPU-s), unless it believes it has set it already. The forkserver
    # starts with the first worker, after that worker's nanny has run this.
    distributed.utils._forkserver_preload_set = True
    preload = [server.preload] if isinstance(server.preload, str) else list(server.preload)
    if __name__ not in preload:
        server.preload = [*preload, __name__]
        argv = server.preload_argv
        if argv and not isinstance(argv[0], str):  # one argv per preload: none for this one
            server.preload_argv = [*argv, []]
