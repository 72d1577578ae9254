"""Where Monte Carlo scenarios run: this process, a local process pool, or a Dask cluster.

All three are driven through one `concurrent.futures` interface (`submit`, futures,
`as_completed`): Dask distributed's `Client.get_executor()` offers the same one as
`ProcessPoolExecutor`, so the code that sends scenarios out is the same for every kind.
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import os
import signal
from collections.abc import Iterator
from contextlib import contextmanager

from gliderplan.contract import MAX_SCENARIOS, MAX_WORKERS
from gliderplan.contract.errors import UsageError


class BackendError(UsageError):
    """A scheduler that cannot be reached or used; the message says what to do."""


def check_run_size(scenarios: int | None, workers: int) -> None:
    """UsageError unless `scenarios` (None: as many as the caller works out) lies in
    1..MAX_SCENARIOS and `workers` 1..MAX_WORKERS: the one test of `gliderplan montecarlo`
    and `gliderplan plan --confidence` / `--occupancy-from-sim`."""
    if scenarios is not None and not 1 <= scenarios <= MAX_SCENARIOS:
        raise UsageError(f"--scenarios {scenarios}: must be between 1 and {MAX_SCENARIOS:,}")
    if workers < 1:
        raise UsageError(f"--workers {workers}: must be at least 1")
    if workers > MAX_WORKERS:
        raise UsageError(f"--workers {workers}: at most {MAX_WORKERS} worker processes "
                         "(a local pool starts them all; this machine has "
                         f"{os.cpu_count() or 1} cores)")


def _ignore_interrupt() -> None:
    """Workers leave Ctrl-C to the parent, which stops handing out work and keeps what
    finished (a worker killed mid-batch would lose it)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextmanager
def scenario_executor(workers: int, scheduler: str | None = None
                      ) -> Iterator[cf.Executor | None]:
    """An executor for `workers` workers: None (this process) for one worker and no
    scheduler; a local process pool; or Dask: `scheduler` "local" starts a LocalCluster of
    `workers` single-threaded processes, "tcp://HOST:PORT" joins a running scheduler."""
    if scheduler is None:
        if workers <= 1:
            yield None
            return
        context = multiprocessing.get_context("fork" if "fork" in
                                              multiprocessing.get_all_start_methods()
                                              else "spawn")
        pool = cf.ProcessPoolExecutor(workers, mp_context=context,
                                      initializer=_ignore_interrupt)
        try:
            yield pool
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
        return
    try:
        import dask
        from distributed import Client, LocalCluster
    except ImportError:
        raise BackendError(f"--scheduler {scheduler}: Dask distributed is not installed "
                           "(pip install 'gliderplan[dask]')") from None
    cluster = None
    try:
        if scheduler == "local":
            # Scenarios are CPU-bound Python in batches of seconds: no sampling profiler in
            # the workers, and glibc's malloc left to size its own heap (Dask's trim
            # threshold sends every large array to mmap, a page fault per page each run).
            environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ"))
            environ.pop("MALLOC_TRIM_THRESHOLD_", None)
            with dask.config.set({"distributed.worker.profile.enabled": False,
                                  "distributed.nanny.pre-spawn-environ": environ}):
                cluster = LocalCluster(n_workers=workers, threads_per_worker=1,
                                       processes=True, dashboard_address=None)
            client = Client(cluster)
        else:
            client = Client(scheduler, timeout=10)
    except (OSError, ValueError) as err:  # ValueError: an address Dask cannot read
        if cluster is not None:
            cluster.close()
        why = "cannot reach it" if isinstance(err, OSError) else \
            "expected local or tcp://HOST:PORT"
        raise BackendError(f"--scheduler {scheduler}: {why}: {err}") from None
    try:
        yield client.get_executor()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
