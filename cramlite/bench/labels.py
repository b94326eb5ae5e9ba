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
#: How a label marks the plan (or the version of a plan or strategy file) of its trials,
#: where a folder holds several: `opm~3f2a9c1b` (trials of two versions never mix).
VERSION_MARK = "~"


def several_backends(rows: Sequence[dict[str, Any]]) -> bool:
    return len({r.get("backend") or "" for r in rows}) > 1


def several_carries(rows: Sequence[dict[str, Any]]) -> bool:
    return len({str(r.get("carry") or 1) for r in rows}) > 1


def _version(row: dict[str, Any]) -> tuple[str, str]:
    return (row.get("plan") or "", row.get("code_hash") or "")


def by_backend(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """The rows, each strategy labelled with its backend where there are several
    (`opm@kinematic`), with how many it carried where that varies (`opm×2`, `opm×1`), and
    with its plan, or its code's hash, where a folder holds trials of several plans or
    versions of one (`opm~3f2a9c1b`: a changed plan or strategy file is a new one)."""
    backends, carries = several_backends(rows), several_carries(rows)
    versions = {_version(r) for r in rows}
    plans = {plan for plan, _ in versions}
    out = []
    for r in rows:
        label = r["strategy"]
        if carries:
            label += f"{CARRY_MARK}{r.get('carry') or 1}"
        if backends:
            label += f"@{r.get('backend') or '?'}"
        if len(versions) > 1:
            plan, code = _version(r)
            label += VERSION_MARK + (code[:8] if code else plan if len(plans) > 1 else "")
        out.append({**r, "strategy_name": r["strategy"], "strategy": label})
    return out


def base_name(label: str) -> str:
    """The strategy's own name in a label: `opm` of `opm×2@kinematic~3f2a9c1b`."""
    return label.split(VERSION_MARK)[0].split("@")[0].split(CARRY_MARK)[0]


def variant(label: str) -> str:
    """What a label adds to the name (`×2@kinematic`): trials compare within one."""
    return label[len(base_name(label)):]
