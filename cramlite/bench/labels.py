"""Rows of a bench that ran on several backends, labelled for summaries and reports.

A bench with `--backends pybullet,kinematic` runs every trial on each; its summary, plots
and report compare the backends side by side by giving each (strategy, backend) its own
label, `opm@kinematic`. The row keeps its strategy's own name in `strategy_name` (what a
command that reruns the trial needs).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any


def several_backends(rows: Sequence[dict[str, Any]]) -> bool:
    return len({r.get("backend") or "" for r in rows}) > 1


def by_backend(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """The rows, each strategy labelled with its backend where there are several."""
    if not several_backends(rows):
        return [{**r, "strategy_name": r["strategy"]} for r in rows]
    return [{**r, "strategy_name": r["strategy"],
             "strategy": f"{r['strategy']}@{r.get('backend') or '?'}"} for r in rows]
