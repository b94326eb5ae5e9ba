"""What the report says about trials: which ones it looks at closely, their steps (from
the task tree), the orders each strategy chose, and their failures in words."""

from __future__ import annotations

from collections import Counter, defaultdict
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

from cramlite.bench.specs import FIXED_ORDER
from cramlite.safe_names import trial_stem

#: A timeline shows the task tree down to this depth (0: the plan's top-level actions).
MAX_DEPTH = 2
#: At most this many failed trials get a timeline of their own (all are listed).
MAX_FAILED_TIMELINES = 40


def ok(row: dict[str, Any]) -> bool:
    return str(row.get("success")) == "True"


def trial_id(row: dict[str, Any]) -> str:
    """A name for a trial usable in file names and anchors: a slug of its setup, plan,
    strategy and index with a hash of them (see `cramlite.safe_names`)."""
    return trial_stem(row["setup"], row.get("plan", ""), row["strategy"], row["trial"],
                      row.get("backend", ""))


def trials_of_interest(rows: Sequence[dict[str, Any]]) -> tuple[list[dict[str, Any]], int]:
    """The first trial of each setup, strategy and backend, then every failed trial (at most
    MAX_FAILED_TIMELINES of them); and how many failed trials were left out."""
    first: dict[tuple[str, str], dict[str, Any]] = {}
    for row in rows:
        if row["strategy"] == FIXED_ORDER:
            continue
        key = (row["setup"], row["strategy"], row.get("backend", ""))
        if key not in first or int(row["trial"]) < int(first[key]["trial"]):
            first[key] = row
    chosen = [first[k] for k in sorted(first)]
    seen = {trial_id(r) for r in chosen}
    failed = sorted((r for r in rows if not ok(r) and trial_id(r) not in seen),
                    key=lambda r: (r["setup"], r["strategy"] == FIXED_ORDER, r["strategy"],
                                   int(r["trial"])))
    return chosen + failed[:MAX_FAILED_TIMELINES], max(0, len(failed) - MAX_FAILED_TIMELINES)


@dataclass(frozen=True)
class Bar:
    """One action of the task tree on the timeline."""

    name: str
    object: str | None
    start: float
    end: float
    depth: int
    failed: bool
    failure: str  #: "Type: message" of a failed action ("" otherwise)


def bars(actions: Sequence[dict[str, Any]], max_depth: int = MAX_DEPTH) -> list[Bar]:
    """The task tree's actions down to `max_depth`, as bars (an unfinished one ends where
    its parent or the trial ends)."""
    out: list[Bar] = []
    end_of_trial = max((n["end_s"] or n["start_s"] for n in _walk(actions, 99)), default=0.0)

    def visit(nodes: Sequence[dict[str, Any]], depth: int, parent_end: float) -> None:
        for node in nodes:
            end = node["end_s"] if node["end_s"] is not None else parent_end
            failure = node.get("failure") or {}
            out.append(Bar(node["name"], node.get("object"), float(node["start_s"]),
                           float(end), depth, node["status"] == "failed",
                           f"{failure.get('type', '')}: {failure.get('message', '')}"
                           if failure else ""))
            if depth < max_depth:
                visit(node.get("children") or [], depth + 1, end)

    visit(actions, 0, end_of_trial)
    return out


def _walk(nodes: Sequence[dict[str, Any]], depth: int) -> Iterator[dict[str, Any]]:
    for node in nodes:
        yield node
        if depth > 0:
            yield from _walk(node.get("children") or [], depth - 1)


@dataclass(frozen=True)
class Step:
    """A row of a trial's step table: an action (or a run of identical failed attempts)."""

    depth: int
    name: str
    object: str
    start: float
    duration: float
    status: str  #: "succeeded", "failed"
    count: int  #: identical consecutive attempts folded into this row
    failure: str


def steps(actions: Sequence[dict[str, Any]]) -> list[Step]:
    """The top-level actions and their children, with durations; instant arm parking is
    left out, and consecutive failed attempts of the same action folded into one row."""
    out: list[Step] = []

    def visit(nodes: Sequence[dict[str, Any]], depth: int) -> None:
        for node in nodes:
            end = node["end_s"] if node["end_s"] is not None else node["start_s"]
            duration = float(end) - float(node["start_s"])
            if node["name"] == "ParkArmsAction" and duration < 1e-6 and depth > 0:
                continue
            failure = node.get("failure") or {}
            text = f"{failure.get('type', '')}: {failure.get('message', '')}" \
                if failure else ""
            step = Step(depth, node["name"], node.get("object") or "",
                        float(node["start_s"]), duration, node["status"], 1, text)
            last = out[-1] if out else None
            if (last is not None and last.depth == depth and last.name == step.name
                    and last.status == "failed" == step.status and duration < 1e-6
                    and last.duration < 1e-6
                    and last.failure.split(":")[0] == text.split(":")[0]):
                out[-1] = Step(depth, last.name, last.object, last.start, 0.0, "failed",
                               last.count + 1, last.failure)
            else:
                out.append(step)
            if depth < 1:
                visit(node.get("children") or [], depth + 1)

    visit(actions, 0)
    return out


def failure_text(row: dict[str, Any]) -> str:
    """What went wrong in a trial, in one line ("" for a success)."""
    if ok(row):
        return ""
    parts = []
    if row.get("error_type"):
        parts.append(f"{row['error_type']}: {row.get('error', '')}".strip())
    for failure in row.get("failures") or []:
        item = f"{failure.get('item')}: " if failure.get("item") else ""
        parts.append(f"{item}{failure.get('type', 'failure')}: "
                     f"{str(failure.get('message', ''))[:300]}")
    off = [name for name, info in (row.get("items") or {}).items()
           if isinstance(info, dict) and not info.get("ok", True)]
    if not parts and off:
        parts.append(f"not at the target: {', '.join(off)}")
    return " | ".join(parts) or "failed (no detail recorded)"


def orders(rows: Sequence[dict[str, Any]], setup: str, strategy: str,
           ) -> list[tuple[str, list[int], int]]:
    """The orders a strategy chose in a setup: (order, its trials, how many failed),
    the most frequent first."""
    trials: dict[str, list[int]] = defaultdict(list)
    failed: Counter[str] = Counter()
    for row in rows:
        if row["setup"] == setup and row["strategy"] == strategy:
            trials[row["order"]].append(int(row["trial"]))
            failed[row["order"]] += not ok(row)
    return sorted(((o, sorted(t), failed[o]) for o, t in trials.items()),
                  key=lambda e: (-len(e[1]), e[1][0]))
