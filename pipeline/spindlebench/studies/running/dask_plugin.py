"""The Dask worker plugin of a study: every worker single-threaded in BLAS.

Its own module because it subclasses ``distributed``'s ``WorkerPlugin`` (Dask refuses
duck-typed plugins), and importing ``distributed`` costs about a CPU-second that a local
study must not pay: ``executor.dask_executor`` imports this module only when it connects to a
cluster. The workers unpickle the plugin by reference, so they import it from the installed
package, as they import the study's tasks.
"""

from __future__ import annotations

from typing import Any

from distributed.diagnostics.plugin import NannyPlugin, WorkerPlugin

from spindlebench.studies.running.executor import one_blas_thread

#: A Dask server's periodic work that a study does not need, and its new period in ms (None:
#: stopped). With the defaults an idle worker, its nanny and the scheduler wake up every 10 to
#: 20 ms (the statistical profiler, the event-loop health "tick") and sample the system every
#: 500 ms: on this machine an idle 1-worker cluster burnt about a tenth of a core, which on a
#: sweep of a few minutes' wall time doubled the CPU of the local pool. The profiler only
#: feeds the dashboard's profile page; the tick only logs a blocked event loop; the system
#: monitor feeds the dashboard and the heartbeats' metrics (kept, less often).
QUIET = {"profile": None, "profile-cycle": None, "tick": 1000, "monitor": 5000}


def quiet(server: Any) -> None:
    """Apply ``QUIET`` to a worker's or nanny's periodic callbacks (those it has)."""
    for name, period_ms in QUIET.items():
        callback = server.periodic_callbacks.get(name)
        if callback is None:
            continue
        if period_ms is None:
            callback.stop()
        else:
            callback.callback_time = period_ms


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
