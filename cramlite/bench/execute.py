"""Running trial specs on a `concurrent.futures` executor, locally or on a cluster.

The local executor is a spawn-based process pool (each worker builds its own worlds);
`dask` uses `Client(...).get_executor()`, a real `concurrent.futures.Executor`, so both
run through the same loop. At most two trials per worker are in flight. A worker that
dies takes the pool down with it: the trials that were in flight are then rerun one by
one in a fresh single-worker pool, so the one that kills its worker is recorded as
`WorkerDied` and the others run normally. Ctrl-C stops cleanly: pending trials are
cancelled, running ones finish and are written.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import signal
from collections import deque
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any

from cramlite.bench.specs import TrialSpec
from cramlite.bench.worker import base_row, run_spec

EXECUTORS = ("local", "dask")
#: After Ctrl-C, how long running trials may take to finish and be written.
INTERRUPT_GRACE_S = 30.0


def _ignore_sigint() -> None:
    """Workers leave Ctrl-C to the parent, which shuts the batch down cleanly."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def local_pool(workers: int) -> ProcessPoolExecutor:
    return ProcessPoolExecutor(max_workers=workers, initializer=_ignore_sigint,
                               mp_context=multiprocessing.get_context("spawn"))


@contextlib.contextmanager
def open_executor(kind: str, workers: int, scheduler: str | None = None) -> Iterator[Executor]:
    if kind == "local":
        pool = local_pool(workers)
        try:
            yield pool
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
        return
    if kind != "dask":
        raise ValueError(f"executor must be one of {EXECUTORS}")
    from distributed import Client, LocalCluster

    cluster = None
    if scheduler:
        client = Client(scheduler)
    else:
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=40)
        client = Client(cluster)
    try:
        yield client.get_executor(pure=False)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


@dataclass
class BatchOutcome:
    ran: int = 0
    failed: int = 0
    worker_deaths: int = 0
    interrupted: bool = False


def failed_row(spec: TrialSpec, error_type: str, message: str) -> dict[str, Any]:
    row = base_row(spec)
    row.update(success=False, error_type=error_type, error=message, worker="")
    return row


def run_batch(specs: list[TrialSpec], record: Callable[[dict[str, Any]], None],
              executor_kind: str = "local", workers: int = 1,
              scheduler: str | None = None) -> BatchOutcome:
    """Run every spec, calling `record(row)` as each finishes (in completion order)."""
    outcome = BatchOutcome()
    pending: deque[TrialSpec] = deque(specs)

    def keep(row: dict[str, Any]) -> None:
        outcome.ran += 1
        outcome.failed += row.get("success") is not True
        record(row)

    try:
        while pending:
            with open_executor(executor_kind, workers, scheduler) as executor:
                suspects = _drain(executor, pending, workers, keep)
            # a worker died: run the trials that were in flight one by one, then go on
            for spec in suspects:
                _run_isolated(spec, keep, outcome)
    except KeyboardInterrupt:
        outcome.interrupted = True
    return outcome


def _drain(executor: Executor, pending: deque[TrialSpec], workers: int,
           keep: Callable[[dict[str, Any]], None]) -> list[TrialSpec]:
    """Run pending specs until done or the pool breaks; returns the in-flight specs of a
    broken pool (the suspects)."""
    in_flight: dict[Future, TrialSpec] = {}
    window = max(1, 2 * workers)
    try:
        while pending or in_flight:
            while pending and len(in_flight) < window:
                spec = pending.popleft()
                try:
                    in_flight[executor.submit(run_spec, spec)] = spec
                except BrokenProcessPool:
                    pending.appendleft(spec)
                    return list(in_flight.values())
            finished, _ = wait(in_flight, return_when=FIRST_COMPLETED)
            broken = []
            for future in finished:
                spec = in_flight.pop(future)
                try:
                    keep(future.result())
                except BrokenProcessPool:
                    broken.append(spec)
                except Exception as exc:  # e.g. dask's KilledWorker: recorded, not lost
                    keep(failed_row(spec, type(exc).__name__, str(exc)))
            if broken:
                return broken + list(in_flight.values())
    except KeyboardInterrupt:
        for future in in_flight:
            future.cancel()  # not started yet: dropped
        running = [f for f in in_flight if not f.cancelled()]
        wait(running, timeout=INTERRUPT_GRACE_S)  # running trials finish and are written
        for future in running:
            if future.done():
                with contextlib.suppress(Exception):
                    keep(future.result())
        raise
    return []


def _run_isolated(spec: TrialSpec, keep: Callable[[dict[str, Any]], None],
                  outcome: BatchOutcome) -> None:
    with open_executor("local", 1) as pool:
        try:
            keep(pool.submit(run_spec, spec).result())
        except BrokenProcessPool:
            outcome.worker_deaths += 1
            keep(failed_row(spec, "WorkerDied",
                            "the worker process died while running this trial"))
