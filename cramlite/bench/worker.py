"""The function batch workers run: one trial from a spec, as a results row.

Each worker process keeps one `TrialRunner` per setup it has seen (its world is built
once and reset between trials). This per-process cache, and the lock that lets only one
trial at a time use it, live only in worker processes started for a batch; the library
itself keeps no global state. The lock matters on a stock `dask worker`, which runs
tasks in several threads of one process: a process has one cache of worlds, one OMPL
random generator and one set of IK solver data, so two trials at once would corrupt
each other.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import threading
import time
import traceback
from typing import Any

from cramlite.bench.specs import FIXED_ORDER, TrialSpec
from cramlite.designators.tasks import actions_only
from cramlite.errors import bounded_text
from cramlite.forking import exit_with_parent

_RUNNERS: dict[tuple[str, str], Any] = {}  # (setup path, hash) -> TrialRunner, per process
_TRIAL_LOCK = threading.Lock()  # one trial at a time in this process
_STARTED: Any = None  # local pool only: a queue that learns when each trial starts


def worker_name() -> str:
    return f"{socket.gethostname()}:{os.getpid()}"


def init_local_worker(started: Any, parent_pid: int) -> None:
    """Initializer of local pool workers: Ctrl-C is the parent's business, and SIGTERM
    ends a worker (a forked one has the bench's own handler until here); tell the parent
    when a trial starts (for its per-trial timeout); exit when the parent is gone (a
    killed bench leaves no workers behind)."""
    global _STARTED
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _STARTED = started
    exit_with_parent(parent_pid)


def run_spec(spec: TrialSpec, lock_timeout_s: float = -1) -> dict[str, Any]:
    """Run one trial; an exception inside it becomes a failed row, never a lost trial.
    Waits at most `lock_timeout_s` (-1: for ever) for another trial of this process."""
    row = base_row(spec)
    if not _TRIAL_LOCK.acquire(timeout=lock_timeout_s):
        row.update(success=False, error_type="WorkerBusy",
                   error=f"another trial has held this worker process for more than "
                         f"{lock_timeout_s:g} s (it timed out and cannot be stopped there)")
        return row
    try:
        if _STARTED is not None:
            _STARTED.put((spec.key, os.getpid()))
        return _run_locked(spec, row)
    finally:
        _TRIAL_LOCK.release()


def _run_locked(spec: TrialSpec, row: dict[str, Any]) -> dict[str, Any]:
    from cramlite.plugins import absolute_reference, trial_code_hash
    from cramlite.trial import TrialRunner

    start = time.perf_counter()
    try:
        cache_key = (spec.setup_path, spec.setup_hash, spec.backend)
        runner = _RUNNERS.get(cache_key)
        if runner is None:
            runner = TrialRunner(spec.setup_path, backend=spec.backend)
            if spec.setup_hash and runner.setup.content_hash != spec.setup_hash:
                runner.close()
                row.update(success=False, error_type="SetupChanged",
                           error=f"{spec.setup_path} changed since the batch started "
                                 f"(content hash {runner.setup.content_hash}, expected "
                                 f"{spec.setup_hash})")
                return row
            _RUNNERS[cache_key] = runner
        strategy = "baseline" if spec.strategy == FIXED_ORDER else spec.strategy
        plan = spec.plan
        if spec.cwd:  # (files named relative to where the bench runs, wherever this runs)
            strategy = absolute_reference(strategy, spec.cwd)
            plan = absolute_reference(plan, spec.cwd)
        if spec.code_hash and trial_code_hash(plan, strategy) != spec.code_hash:
            row.update(success=False, error_type="CodeChanged",
                       error=f"the plan or strategy file changed since the batch started "
                             f"(hash {trial_code_hash(plan, strategy) or 'none'}, expected "
                             f"{spec.code_hash})")
            return row
        from cramlite.designators.injection import parse_inject

        result = runner.run(strategy, plan, spec.seed,
                            order=list(spec.given_order) or None, trace=spec.trace or None,
                            inject=parse_inject(spec.inject), carry=spec.carry)
    except (Exception, SystemExit, KeyboardInterrupt) as exc:  # recorded, the batch goes on
        if isinstance(exc, KeyboardInterrupt) and not _interrupts_are_code():
            raise  # (a real Ctrl-C to a process that takes it: stop)
        row.update(success=False, error_type=type(exc).__name__,
                   error=bounded_text(f"{exc}".strip()) or
                   (f"{type(exc).__name__} raised by the trial's code" if not isinstance(
                       exc, Exception) else traceback.format_exc(limit=1).strip()),
                   wall_s=time.perf_counter() - start)
        return row
    row.update(success=result.success, order=" ".join(result.order),
               failures=json.dumps(result.failures),
               failure_types=" ".join(f["type"] for f in result.failures),
               injected=json.dumps(result.injected, sort_keys=True),
               base_path_m=result.base_path_m,
               straight_line_m="" if result.straight_line_m is None else result.straight_line_m,
               wall_s=result.wall_s, drive_s=result.drive_s, arm_s=result.arm_s,
               open_close_s=result.open_close_s, robot_time_s=result.robot_time_s,
               task_time_s=result.task_time_s,
               items=json.dumps(result.items),
               actions=json.dumps(actions_only(result.actions), separators=(",", ":")),
               driven_path=json.dumps(result.driven_path, separators=(",", ":")),
               trips=json.dumps(result.trips, separators=(",", ":")))
    return row


def _interrupts_are_code() -> bool:
    """A KeyboardInterrupt here was raised by a trial's code (a plan or strategy), not by
    Ctrl-C: local workers ignore SIGINT (the bench stops them), and a Dask worker runs
    trials in threads that signals never reach."""
    return signal.getsignal(signal.SIGINT) == signal.SIG_IGN or \
        threading.current_thread() is not threading.main_thread()


def base_row(spec: TrialSpec) -> dict[str, Any]:
    return {"setup": spec.setup, "setup_hash": spec.setup_hash, "plan": spec.plan,
            "strategy": spec.strategy, "code_hash": spec.code_hash,
            "given_order": " ".join(spec.given_order),
            "backend": spec.backend, "inject": spec.inject, "injected": "{}",
            "carry": spec.carry, "trips": "[]",
            "trial": spec.trial, "seed": spec.seed, "batch_seed": spec.batch_seed,
            "success": False, "order": "", "failures": "[]", "failure_types": "",
            "base_path_m": "", "straight_line_m": "", "wall_s": "", "drive_s": "", "arm_s": "",
            "open_close_s": "", "robot_time_s": "", "task_time_s": "", "items": "{}",
            "actions": "[]",
            "driven_path": "[]",
            "error_type": "", "error": "", "worker": worker_name()}
