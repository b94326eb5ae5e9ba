"""Backends side by side: the same trial run on several backends (`bench --backends A,B`),
compared on what each one measures.

The planner makes driving and arm times, so they agree by construction; what a simulator
decides is where items end (settled, pushed) and so whether the trial succeeded, and from
that the orders of the strategies that look at where items are. Each trial run on every
backend is compared with the first backend's: the same order, the same success, and every
item within `tolerance_m` of where the first backend left it.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Sequence
from typing import Any

from cramlite.safe_json import parse_json

#: Items further apart than this (m) between two backends' ends of a trial: they disagree.
AGREEMENT_TOLERANCE_M = 0.01


def _mapping(row: dict[str, Any], column: str) -> dict[str, Any]:
    """A JSON-object column of a row (text in trials.csv, already parsed by the report);
    {} if it is empty or not an object."""
    value = row.get(column) or {}
    if isinstance(value, str):
        try:
            value = parse_json(value)
        except ValueError:
            return {}
    return value if isinstance(value, dict) else {}


def _positions(row: dict[str, Any]) -> dict[str, list[float]]:
    """Where each item ended (the `items` column)."""
    items = _mapping(row, "items")
    return {n: v["position"] for n, v in items.items()
            if isinstance(v, dict) and isinstance(v.get("position"), list)}


def backend_agreement(rows: Sequence[dict[str, Any]],
                      tolerance_m: float = AGREEMENT_TOLERANCE_M) -> list[dict[str, Any]]:
    """One entry per trial and other backend: the first backend (in the rows' order of
    backends, sorted) against each other one. Empty when the rows are of one backend."""
    trials: dict[tuple, dict[str, dict[str, Any]]] = defaultdict(dict)
    for row in rows:
        key = (row["setup"], row.get("strategy_name", row["strategy"]),
               row.get("given_order", ""), str(row["trial"]))
        trials[key][row.get("backend") or ""] = row
    backends = sorted({b for by in trials.values() for b in by})
    if len(backends) < 2:
        return []
    out = []
    for (setup, strategy, _, trial), by in trials.items():
        first = next((b for b in backends if b in by), None)
        for other in (b for b in backends if b in by and b != first):
            a, b = by[first], by[other]
            pa, pb = _positions(a), _positions(b)
            gaps = {n: math.dist(pa[n], pb[n]) for n in pa if n in pb}
            worst = max(gaps, key=gaps.get, default="")
            same_order = a.get("order", "") == b.get("order", "")
            same_success = str(a.get("success")) == str(b.get("success"))
            gap = gaps.get(worst, float("nan"))
            out.append({"setup": setup, "strategy": strategy, "trial": trial,
                        "backends": (first, other), "same_order": same_order,
                        "same_success": same_success, "gap_m": gap, "worst_item": worst,
                        "agree": same_order and same_success and bool(gaps)
                        and gap <= tolerance_m})
    return sorted(out, key=lambda x: (x["setup"], x["strategy"], int(x["trial"])
                                      if x["trial"].isdigit() else 0))


def agreement_markdown(entries: Sequence[dict[str, Any]]) -> list[str]:
    """The summary's lines on the backends' agreement (none for one backend)."""
    if not entries:
        return []
    pairs = sorted({e["backends"] for e in entries})
    agree = sum(e["agree"] for e in entries)
    gaps = [e["gap_m"] for e in entries if not math.isnan(e["gap_m"])]
    lines = ["", "Backends side by side (" + "; ".join(f"{a} vs {b}" for a, b in pairs) +
             f"): {agree} of {len(entries)} trials agree (same order, same success, every "
             f"item within {AGREEMENT_TOLERANCE_M * 100:g} cm)"
             + (f"; items at most {max(gaps) * 100:.2f} cm apart." if gaps else ".")]
    differ = [e for e in entries if not e["agree"]]
    if differ:
        lines += ["", "| setup | strategy | trial | backends | order | success | "
                  "largest item gap |", "|---|---|---|---|---|---|---|"]
        for x in differ:
            gap = "–" if math.isnan(x["gap_m"]) else f"{x['gap_m'] * 100:.2f} cm " \
                                                     f"({x['worst_item']})"
            lines.append(f"| {x['setup']} | {x['strategy']} | {x['trial']} | "
                         f"{x['backends'][0]} vs {x['backends'][1]} | "
                         f"{'same' if x['same_order'] else 'differs'} | "
                         f"{'same' if x['same_success'] else 'differs'} | {gap} |")
    return lines


def injection_counts(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per strategy (label), over the trials with failures injected (`--inject`): the
    failures drawn by kind, the trials, those that still succeeded (recovered), and the
    items finally lost (not where they belong at the end)."""
    out: dict[str, dict[str, Any]] = {}
    for row in rows:
        if not row.get("inject"):
            continue
        drawn = _mapping(row, "injected")
        entry = out.setdefault(row["strategy"], {"strategy": row["strategy"],
                                                 "inject": row["inject"], "trials": 0,
                                                 "with_failures": 0, "recovered": 0,
                                                 "lost": 0, "drawn": {}})
        entry["trials"] += 1
        if drawn:
            entry["with_failures"] += 1
            entry["recovered"] += str(row.get("success")) == "True"
        for kind, n in drawn.items():
            entry["drawn"][kind] = entry["drawn"].get(kind, 0) + int(n)
        items = _mapping(row, "items")
        entry["lost"] += sum(1 for v in items.values() if isinstance(v, dict)
                             and v.get("ok") is False)
    return sorted(out.values(), key=lambda e: e["strategy"])


def injection_markdown(entries: Sequence[dict[str, Any]]) -> list[str]:
    """The summary's lines on injected failures (none without `--inject`)."""
    lines = []
    for e in entries:
        drawn = ", ".join(f"{k} {n}" for k, n in sorted(e["drawn"].items())) or "none drawn"
        lines.append(f"- {e['strategy']} ({e['inject']}): {e['trials']} trials, failures "
                     f"injected: {drawn}; {e['recovered']} of the {e['with_failures']} trials "
                     f"with failures still set everything in place; {e['lost']} items lost")
    return ["", "Injected failures (--inject):", *lines] if lines else []
