"""Where Monte Carlo scenarios run: this process, a local process pool, or a Dask cluster.

All three are driven through one `concurrent.futures` interface (`submit`, futures,
`as_completed`): Dask distributed's `Client.get_executor()` offers the same one as
`ProcessPoolExecutor`, so the code that sends scenarios out is the same for every kind.
"""

from __future__ import annotations

import concurrent.futures as cf
import logging
import multiprocessing
import os
import signal
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager

from gliderplan.contract import MAX_SCENARIOS, MAX_WORKERS, interrupts
from gliderplan.contract.errors import UsageError

DASK_CLOSE_S = 20.0  # [s] a Dask client or local cluster is given this long to close
DASK_STOP_CLOSE_S = 5.0  # [s] ... when a stop signal ends the run
STOP_POLL_S = 0.2  # [s] how often a run on workers looks for a stop signal


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
    """Workers leave Ctrl-C and SIGTERM (sent to the whole process group) to the parent,
    which keeps what finished and stops them (`halt`): a worker never hands back a
    scenario cut short as if it were one flown."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)


def halt(executor: cf.Executor | None) -> None:
    """Stop `executor`'s work now (an interrupted run): nothing more is handed out, and
    a local pool's workers are killed, batches they were flying and all; Dask's tasks end
    when its client and cluster close (`scenario_executor`: a task whose client went away
    is cancelled)."""
    if not isinstance(executor, cf.ProcessPoolExecutor):
        return  # Dask: its tasks end when the client and the cluster close
    processes = list((getattr(executor, "_processes", None) or {}).values())
    calls = getattr(executor, "_call_queue", None)
    if calls is not None:  # its feeder may be blocked on a full pipe the killed workers no
        calls.cancel_join_thread()  # longer read: not joined at exit (it would hang there)
    executor.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        if process.is_alive():
            process.kill()
    for process in processes:
        process.join(5.0)


def gather(executor: cf.Executor | None, work: Callable, tasks: Sequence[tuple],
           collect: Callable[[tuple, object], None]) -> bool:
    """Run `work(*task)` for each of `tasks`, in this process without an executor (one
    after the other) or through `executor`, and hand each result to `collect(task,
    result)` as it finishes. True if Ctrl-C or SIGTERM stopped it: at once, workers and
    all (`halt`), with only what finished collected, never a task cut short (the one
    definition of how scenarios and flights sent out stop: `montecarlo`, `plan
    --confidence`, `fleet sim`, `fleet montecarlo`)."""
    try:
        if executor is None:
            for task in tasks:
                interrupts.raise_if_stopped()
                collect(task, work(*task))
        else:
            # a stop while a pool forks its workers waits until they are forked (raised
            # in an at-fork hook, it would be lost)
            with interrupts.deferred(reraise=True):
                pending = {executor.submit(work, *task): task for task in tasks}
            waiting = set(pending)
            while waiting:
                # looked at every STOP_POLL_S: a stop that a scheduler's code swallowed
                # on the main thread still ends the run at once
                done, waiting = cf.wait(waiting, STOP_POLL_S, cf.FIRST_COMPLETED)
                interrupts.raise_if_stopped()
                for future in done:
                    collect(pending[future], future.result())
        interrupts.raise_if_stopped()
    except KeyboardInterrupt:
        halt(executor)  # what was not handed out is cancelled, workers and all
        return True
    return False


def _workers_ignoring_interrupt() -> None:
    """Dask's workers are started by a fork server whose first preload ignores Ctrl-C
    (`sim.worker_signals`): they inherit that, while this process keeps taking it."""
    import dask
    from distributed.utils import get_mp_context

    dask.config.set({"distributed.worker.multiprocessing-method": "forkserver"})
    get_mp_context().set_forkserver_preload(["gliderplan.sim.worker_signals", "distributed"])


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
    cluster = client = None
    try:
        # A stop signal while Dask starts waits until it has started (cut half-way, it
        # leaves processes that its exit hook then fails to close), then stops the run.
        with interrupts.deferred(reraise=True):
            if scheduler == "local":
                # Scenarios are CPU-bound Python in batches of seconds: no sampling profiler
                # in the workers, and glibc's malloc left to size its own heap (Dask's trim
                # threshold sends every large array to mmap, a page fault per page each run).
                environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ"))
                environ.pop("MALLOC_TRIM_THRESHOLD_", None)
                _workers_ignoring_interrupt()
                with dask.config.set({"distributed.worker.profile.enabled": False,
                                      "distributed.nanny.pre-spawn-environ": environ}):
                    # its workers' own logs (a heartbeat that failed as the cluster
                    # closed on a stop) are not the user's concern: a task's error comes
                    # back to us with its future
                    cluster = LocalCluster(n_workers=workers, threads_per_worker=1,
                                           processes=True, dashboard_address=None,
                                           silence_logs=logging.CRITICAL)
                client = Client(cluster)
            else:
                client = Client(scheduler, timeout=10)
    except (OSError, ValueError) as err:  # ValueError: an address Dask cannot read
        _close(client, cluster)
        why = "cannot reach it" if isinstance(err, OSError) else \
            "expected local or tcp://HOST:PORT"
        raise BackendError(f"--scheduler {scheduler}: {why}: {err}") from None
    except BaseException:
        _close(client, cluster)
        raise
    try:
        yield client.get_executor()
    finally:
        _close(client, cluster)


def _close(client, cluster) -> None:  # noqa: ANN001 (Dask's, imported when used)
    """Close a Dask client and the local cluster it runs on, as far as they started; a
    stop signal meanwhile waits (a close cut half-way leaves processes behind)."""
    with interrupts.deferred(reraise=True):
        for closing in (client, cluster):
            if closing is None:
                continue
            try:
                closing.close(timeout=DASK_STOP_CLOSE_S if interrupts.stopped()
                              else DASK_CLOSE_S)
            except Exception:  # noqa: BLE001 (Dask's own trouble closing)
                if not interrupts.stopped():
                    raise  # stopping anyway, it is not the run's: the exit says stopped
