"""The function batch workers run: one trial from a spec, as a results row.

Each worker process keeps one `TrialRunner` per setup it has seen (its world is built
once and reset between trials). This per-process cache lives only in worker processes
started for a batch; the library itself keeps no global state.
"""

from __future__ import annotations

import json
import os
import socket
import time
import traceback
from typing import Any

from cramlite.bench.specs import FIXED_ORDER, TrialSpec

_RUNNERS: dict[str, Any] = {}  # setup path -> TrialRunner, in this worker process only


def worker_name() -> str:
    return f"{socket.gethostname()}:{os.getpid()}"


def run_spec(spec: TrialSpec) -> dict[str, Any]:
    """Run one trial; an exception inside it becomes a failed row, never a lost trial."""
    from cramlite.trial import TrialRunner

    row = base_row(spec)
    start = time.perf_counter()
    try:
        runner = _RUNNERS.get(spec.setup_path)
        if runner is None:
            runner = _RUNNERS[spec.setup_path] = TrialRunner(spec.setup_path)
        strategy = "baseline" if spec.strategy == FIXED_ORDER else spec.strategy
        result = runner.run(strategy, spec.plan, spec.seed,
                            order=list(spec.given_order) or None, trace=spec.trace or None)
    except Exception as exc:  # recorded, the batch goes on
        row.update(success=False, error_type=type(exc).__name__,
                   error=f"{exc}".strip() or traceback.format_exc(limit=1).strip(),
                   wall_s=time.perf_counter() - start)
        return row
    row.update(success=result.success, order=" ".join(result.order),
               failures=json.dumps(result.failures),
               failure_types=" ".join(f["type"] for f in result.failures),
               base_path_m=result.base_path_m, straight_line_m=result.straight_line_m,
               wall_s=result.wall_s, drive_s=result.drive_s, arm_s=result.arm_s,
               robot_time_s=result.robot_time_s,
               items=json.dumps(result.items))
    return row


def base_row(spec: TrialSpec) -> dict[str, Any]:
    return {"setup": spec.setup, "plan": spec.plan, "strategy": spec.strategy,
            "given_order": " ".join(spec.given_order), "trial": spec.trial, "seed": spec.seed,
            "batch_seed": spec.batch_seed, "success": False, "order": "", "failures": "[]",
            "failure_types": "", "base_path_m": "", "straight_line_m": "", "wall_s": "",
            "drive_s": "", "arm_s": "",
            "robot_time_s": "", "items": "{}", "error_type": "", "error": "",
            "worker": worker_name()}
