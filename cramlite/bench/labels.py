"""Rows of a bench that ran on several backends, labelled for summaries and reports.

A bench with `--backends pybullet,kinematic` runs every trial on each; its summary, plots
and report compare the backends side by side by giving each (strategy, backend) its own
label, `opm@kinematic`; one with `--carry 1,2` gives each (strategy, carry) its own,
`opm×1` and `opm×2`. The row keeps its strategy's own name in `strategy_name` (what a
command that reruns the trial needs).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

#: How a label marks trials that carried several items at once: `opm×2`.
CARRY_MARK = "×"


def several_backends(rows: Sequence[dict[str, Any]]) -> bool:
    return len({r.get("backend") or "" for r in rows}) > 1


def several_carries(rows: Sequence[dict[str, Any]]) -> bool:
    return len({str(r.get("carry") or 1) for r in rows}) > 1


def by_backend(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """The rows, each strategy labelled with its backend where there are several
    (`opm@kinematic`) and with how many it carried where that varies (`opm×2`, `opm×1`)."""
    backends, carries = several_backends(rows), several_carries(rows)
    out = []
    for r in rows:
        label = r["strategy"]
        if carries:
            label += f"{CARRY_MARK}{r.get('carry') or 1}"
        if backends:
            label += f"@{r.get('backend') or '?'}"
        out.append({**r, "strategy_name": r["strategy"], "strategy": label})
    return out


def base_name(label: str) -> str:
    """The strategy's own name in a label: `opm` of `opm×2@kinematic`."""
    return label.split("@")[0].split(CARRY_MARK)[0]


def variant(label: str) -> str:
    """What a label adds to the name (`×2@kinematic`): trials compare within one."""
    return label[len(base_name(label)):]
