"""Running trial specs on a `concurrent.futures` executor, locally or on a cluster.

The local executor is a process pool whose workers are forked from the bench where that is
safe (`cramlite.forking.fork_is_safe`: they start with its imports, ~0.3 s of CPU each),
else spawned; each worker builds its own worlds;
`dask` uses `Client(...).get_executor()`, a real `concurrent.futures.Executor`, so both
run through the same loop, which pulls specs from an iterator as trials finish (at most
two per worker in flight). Only what a trial itself raises becomes a failed row; an
error while recording a row (a closed terminal, a full disk) stops the batch instead.

Faults:
- A trial that runs longer than the trial timeout is recorded as `Timeout`. Locally its
  worker is killed and replaced; on Dask (which cannot stop a running task) the timeout
  counts from submission and the worker's thread stays busy, so that worker's next
  trials wait at most one timeout and are then recorded as `WorkerBusy`.
- A local worker that dies takes the pool down with it: the trials that were in flight
  are rerun one by one in a fresh single-worker pool, so the one that kills its worker
  is recorded as `WorkerDied` and the others run normally.
- Ctrl-C: pending trials are dropped, running ones get INTERRUPT_GRACE_S to finish and
  be written; a second Ctrl-C or SIGTERM (`StopNow`) stops at once. On every way out
  (done, Ctrl-C, SIGTERM, an exception) the local workers are terminated, and a worker
  whose bench was killed exits by itself within a second.
"""

from __future__ import annotations

import contextlib
import importlib.util
import multiprocessing
import os
import queue
import signal
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, CancelledError, Future, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any

from cramlite.bench.specs import TrialSpec
from cramlite.bench.worker import base_row, init_local_worker, run_spec

EXECUTORS = ("local", "dask")
#: After Ctrl-C, how long running trials may take to finish and be written.
INTERRUPT_GRACE_S = 30.0
#: Default per-trial timeout: a trial takes seconds; one that runs this long hangs.
DEFAULT_TRIAL_TIMEOUT_S = 300.0
#: How long connecting to a Dask scheduler may take.
DASK_CONNECT_TIMEOUT_S = 10.0
#: How often the loop looks at running trials (for timeouts) while none finishes.
POLL_S = 0.2

Record = Callable[[dict[str, Any]], None]
Notify = Callable[[str], None]


class StopNow(KeyboardInterrupt):
    """SIGTERM or a second Ctrl-C: stop without waiting for running trials."""


class SchedulerUnreachable(Exception):
    """The Dask scheduler could not be reached or its address is malformed."""


@dataclass
class BatchOutcome:
    ran: int = 0
    failed: int = 0
    worker_deaths: int = 0
    timeouts: int = 0
    interrupted: bool = False
    stopped_now: bool = False


def failed_row(spec: TrialSpec, error_type: str, message: str) -> dict[str, Any]:
    row = base_row(spec)
    row.update(success=False, error_type=error_type, error=message, worker="")
    return row


# -- pools -------------------------------------------------------------------------------
class LocalPool:
    """A process pool (forked workers where `fork_is_safe()`, else spawned) whose workers
    report when each trial starts (so a trial that runs too long can be stopped by
    killing its worker), terminated rather than waited for when a batch stops early."""

    kind = "local"

    def __init__(self, workers: int):
        from concurrent.futures import ProcessPoolExecutor

        from cramlite.forking import fork_is_safe

        self.start_method = "fork" if fork_is_safe() else "spawn"
        context = multiprocessing.get_context(self.start_method)
        self.workers = workers
        self._started = context.Queue()
        self._starts: dict[tuple[str, ...], tuple[int, float]] = {}
        self.executor = ProcessPoolExecutor(max_workers=workers, mp_context=context,
                                            initializer=init_local_worker,
                                            initargs=(self._started, os.getpid()))

    def submit(self, spec: TrialSpec) -> Future:
        from cramlite.forking import quiet_fork

        self._starts.pop(spec.key, None)
        with quiet_fork():  # (the first submission starts the workers)
            return self.executor.submit(run_spec, spec)

    def running_since(self, spec: TrialSpec) -> float | None:
        while True:
            try:
                key, pid = self._started.get_nowait()
            except (queue.Empty, OSError, ValueError):
                break
            self._starts[key] = (pid, time.monotonic())
        start = self._starts.get(spec.key)
        return None if start is None else start[1]

    def stop(self, future: Future, spec: TrialSpec) -> bool:
        """Kill the worker running `spec`, and with it this pool (the other trials in
        flight are rerun in a new one); returns True: the pool is gone."""
        pid = self._starts.get(spec.key, (None, 0.0))[0]
        if pid is not None:
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
        self.terminate()
        return True

    def terminate(self) -> None:
        """Kill every worker now (the executor has no public call for it before 3.14)."""
        kill = getattr(self.executor, "kill_workers", None)
        if kill is not None:  # pragma: no cover - Python >= 3.14
            kill()
        else:
            for process in list((getattr(self.executor, "_processes", None) or {}).values()):
                with contextlib.suppress(Exception):
                    process.kill()
        self.executor.shutdown(wait=True, cancel_futures=True)
        self._close_queue()

    def close(self) -> None:
        self.executor.shutdown(wait=True, cancel_futures=True)
        self._close_queue()

    def _close_queue(self) -> None:
        with contextlib.suppress(Exception):
            self._started.close()
            self._started.join_thread()


class DaskPool:
    """A Dask cluster through `Client.get_executor()`: the given scheduler, or a local
    cluster of single-threaded worker processes."""

    kind = "dask"

    def __init__(self, workers: int | None, scheduler: str | None, trial_timeout_s: float):
        from distributed import Client, LocalCluster

        self.cluster = None
        if scheduler:
            try:
                self.client = Client(scheduler, timeout=DASK_CONNECT_TIMEOUT_S)
            except (OSError, TimeoutError, ValueError, TypeError) as exc:
                raise SchedulerUnreachable(f"cannot reach the Dask scheduler at {scheduler} "
                                           f"({type(exc).__name__}: {exc})") from None
        else:
            self.cluster = LocalCluster(n_workers=workers or 1, threads_per_worker=1,
                                        processes=True, dashboard_address=None,
                                        silence_logs=40)
            self.client = Client(self.cluster)
        processes = len(self.client.scheduler_info().get("workers", {})) or 1
        self.workers = workers or processes
        self.trial_timeout_s = trial_timeout_s
        self.executor = self.client.get_executor(pure=False)
        self._submitted: dict[tuple[str, ...], float] = {}

    def submit(self, spec: TrialSpec) -> Future:
        self._submitted[spec.key] = time.monotonic()
        return self.executor.submit(run_spec, spec, self.trial_timeout_s)

    def running_since(self, spec: TrialSpec) -> float | None:
        return self._submitted.get(spec.key)

    def stop(self, future: Future, spec: TrialSpec) -> bool:
        future.cancel()  # a running Dask task cannot be stopped; its thread stays busy
        return False

    def terminate(self) -> None:
        self.close()

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self.executor.shutdown(wait=False)
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


@contextlib.contextmanager
def open_pool(kind: str, workers: int, scheduler: str | None = None,
              trial_timeout_s: float = DEFAULT_TRIAL_TIMEOUT_S) -> Iterator[Any]:
    """A pool that is closed normally when the block ends and terminated when it is left
    by an exception (Ctrl-C, SIGTERM, a failure to record a row)."""
    if kind not in EXECUTORS:
        raise ValueError(f"executor must be one of {EXECUTORS}")
    pool = LocalPool(workers) if kind == "local" else \
        DaskPool(workers, scheduler, trial_timeout_s)
    try:
        yield pool
    except BaseException:
        pool.terminate()
        raise
    pool.close()


#: Dask address schemes a bench can use (inproc:// works only inside one process).
SCHEDULER_SCHEMES = ("tcp", "tls", "ws", "wss", "ucx")


#: The modules that give Dask its ucx:// protocol.
UCX_MODULES = ("ucp", "distributed_ucxx")


def check_scheduler(address: str) -> None:
    """Fail fast on a malformed or unreachable scheduler address (SchedulerUnreachable):
    the scheme must be one Dask knows, and a host:port must accept a connection."""
    import socket

    try:
        from distributed.comm import parse_address, parse_host_port
    except ImportError:
        raise SchedulerUnreachable("the dask executor needs Dask: pip install "
                                   "'cramlite[dask]'") from None
    expected = "expected e.g. tcp://HOST:8786"
    try:
        protocol, location = parse_address(address, strict=False)
        if protocol not in SCHEDULER_SCHEMES:
            raise ValueError(f"scheme {protocol!r} is not one of {', '.join(SCHEDULER_SCHEMES)}")
        if protocol == "ucx" and not any(importlib.util.find_spec(m) for m in UCX_MODULES):
            raise SchedulerUnreachable(f"{address}: the ucx:// protocol needs UCX for Dask "
                                       "(ucx-py or distributed-ucxx), which is not installed; "
                                       f"{expected}")
        host, port = parse_host_port(location)
    except (ValueError, TypeError) as exc:
        raise SchedulerUnreachable(f"malformed Dask scheduler address {address!r} ({exc}); "
                                   f"{expected}") from None
    if not host or not isinstance(port, int) or not 0 < port < 65536:
        raise SchedulerUnreachable(f"malformed Dask scheduler address {address!r}; {expected}")
    try:
        socket.create_connection((host, port), timeout=DASK_CONNECT_TIMEOUT_S).close()
    except OSError as exc:
        raise SchedulerUnreachable(f"cannot reach the Dask scheduler at {address} "
                                   f"({exc.strerror or exc})") from None


# -- the batch loop ----------------------------------------------------------------------
class _Pending:
    """Specs still to run: requeued ones first, then the rest of the stream."""

    def __init__(self, specs: Iterable[TrialSpec]):
        self._stream = iter(specs)
        self._requeued: deque[TrialSpec] = deque()

    def pop(self) -> TrialSpec | None:
        if self._requeued:
            return self._requeued.popleft()
        return next(self._stream, None)

    def requeue(self, specs: Iterable[TrialSpec]) -> None:
        self._requeued.extendleft(reversed(list(specs)))


def run_batch(specs: Iterable[TrialSpec], record: Record, executor_kind: str = "local",
              workers: int = 1, scheduler: str | None = None,
              trial_timeout_s: float = DEFAULT_TRIAL_TIMEOUT_S,
              notify: Notify | None = None) -> BatchOutcome:
    """Run every spec, calling `record(row)` as each finishes (in completion order)."""
    outcome = BatchOutcome()
    say = notify or (lambda message: None)
    pending = _Pending(specs)

    def keep(row: dict[str, Any]) -> None:
        outcome.ran += 1
        outcome.failed += row.get("success") is not True
        outcome.timeouts += row.get("error_type") == "Timeout"
        record(row)

    try:
        while True:
            with open_pool(executor_kind, workers, scheduler, trial_timeout_s) as pool:
                finished, suspects = _drain(pool, pending, keep, trial_timeout_s, say)
            if suspects:
                say(f"a worker process died with {len(suspects)} trial(s) in flight; "
                    "rerunning them one at a time in a fresh worker")
            for spec in suspects:
                _run_isolated(spec, keep, outcome, trial_timeout_s, say)
            if finished:
                break
    except KeyboardInterrupt as exc:
        outcome.interrupted = True
        outcome.stopped_now = isinstance(exc, StopNow)
    return outcome


def _drain(pool: Any, pending: _Pending, keep: Record, timeout_s: float, say: Notify,
           ) -> tuple[bool, list[TrialSpec]]:
    """Run specs until none is left (True, []) or the pool breaks: (False, suspects), the
    trials in flight when a worker died unasked; trials in flight when a worker was killed
    for a timeout are requeued instead."""
    in_flight: dict[Future, TrialSpec] = {}
    window = max(1, 2 * pool.workers)
    try:
        while True:
            while len(in_flight) < window:
                spec = pending.pop()
                if spec is None:
                    break
                try:
                    in_flight[pool.submit(spec)] = spec
                except BrokenProcessPool:
                    pending.requeue([spec])
                    return False, list(in_flight.values())
            if not in_flight:
                return True, []
            finished, _ = wait(in_flight, timeout=POLL_S, return_when=FIRST_COMPLETED)
            broken = []
            for future in finished:
                spec = in_flight.pop(future)
                try:
                    row = future.result()
                except BrokenProcessPool:
                    broken.append(spec)
                    continue
                except CancelledError:
                    continue
                except Exception as exc:  # e.g. dask's KilledWorker: recorded, not lost
                    if type(exc).__name__ == "KilledWorker":
                        say(f"a Dask worker died running {_label(spec)}")
                    row = failed_row(spec, type(exc).__name__, str(exc))
                keep(row)  # outside the try: an error in recording is not a trial failure
            if broken:
                return False, broken + list(in_flight.values())
            now = time.monotonic()
            for future, spec in list(in_flight.items()):
                since = pool.running_since(spec)
                if since is None or now - since <= timeout_s or future.done():
                    continue
                del in_flight[future]
                keep(failed_row(spec, "Timeout", f"ran longer than the trial timeout "
                                                 f"({timeout_s:g} s); stopped"))
                if pool.stop(future, spec):  # the local pool is broken now: start afresh
                    say(f"{_label(spec)} exceeded the trial timeout ({timeout_s:g} s): "
                        "recorded as Timeout, its worker killed and replaced")
                    pending.requeue(in_flight.values())
                    return False, []
                say(f"{_label(spec)} exceeded the trial timeout ({timeout_s:g} s): recorded "
                    "as Timeout; its Dask worker thread stays busy until the trial ends")
    except KeyboardInterrupt as exc:
        _finish_running(in_flight, keep, say, stop_now=isinstance(exc, StopNow))
        raise


def _finish_running(in_flight: dict[Future, TrialSpec], keep: Record, say: Notify,
                    stop_now: bool) -> None:
    """After Ctrl-C: drop trials not started, let running ones finish and be written
    (for at most INTERRUPT_GRACE_S; a second Ctrl-C stops at once)."""
    for future in in_flight:
        future.cancel()  # not started yet: dropped
    running = [f for f in in_flight if not f.cancelled()]
    if running and not stop_now:
        say(f"interrupted: waiting up to {INTERRUPT_GRACE_S:g} s for {len(running)} running "
            "trial(s) to finish (Ctrl-C again to stop now)")
        with contextlib.suppress(KeyboardInterrupt):
            wait(running, timeout=INTERRUPT_GRACE_S)
    for future in running:
        if future.done() and not future.cancelled():
            with contextlib.suppress(Exception):
                keep(future.result())


def _run_isolated(spec: TrialSpec, keep: Record, outcome: BatchOutcome, timeout_s: float,
                  say: Notify) -> None:
    pending = _Pending([spec])
    while True:
        with open_pool("local", 1) as pool:
            finished, suspects = _drain(pool, pending, keep, timeout_s, say)
        if suspects:
            outcome.worker_deaths += 1
            say(f"{_label(spec)} killed its worker process: recorded as WorkerDied")
            keep(failed_row(spec, "WorkerDied",
                            "the worker process died while running this trial"))
            return
        if finished:
            return


def _label(spec: TrialSpec) -> str:
    order = f" [{' '.join(spec.given_order)}]" if spec.given_order else ""
    return f"trial {spec.setup}/{spec.strategy}{order}/{spec.trial}"
