"""The Dask worker plugin of a study: every worker single-threaded in BLAS.

Its own module because it subclasses ``distributed``'s ``WorkerPlugin`` (Dask refuses
duck-typed plugins), and importing ``distributed`` costs about a CPU-second that a local
study must not pay: ``executor.dask_executor`` imports this module only when it connects to a
cluster. The workers unpickle the plugin by reference, so they import it from the installed
package, as they import the study's tasks.
"""

from __future__ import annotations

from typing import Any

from distributed.diagnostics.plugin import WorkerPlugin

from spindlebench.studies.running.executor import one_blas_thread


class OneBlasThread(WorkerPlugin):
    """``executor.one_blas_thread`` in every worker when it starts, or at once in the workers
    already running when the plugin is registered. A worker runs ``nthreads`` tasks at a time;
    a multi-threaded BLAS under each oversubscribes the cores as in the local pool, where two
    OpenBLAS thread pools spinning against each other made 2 workers slower than 1."""

    name = "spindlebench-one-blas-thread"

    def setup(self, worker: Any) -> None:
        one_blas_thread()
