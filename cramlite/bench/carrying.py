"""Two hands against one: what carrying two items at once saves (`bench --carry 1,2`).

Each trial run with both carries is a pair (same setup, strategy, backend, trial index,
seed): the saving is the carry-1 value minus the carry-2 value of robot time, driven path
and trips. Per strategy, per setup and pooled over setups, with a paired Wilcoxon
signed-rank test over the pooled pairs (with 5 pairs per setup, a per-setup test cannot
go below p = 0.0625; pooled over setups it can). Only pairs in which both trials
succeeded count.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from typing import Any

import numpy as np

from cramlite.bench.labels import base_name
from cramlite.bench.specs import FIXED_ORDER
from cramlite.safe_json import parse_json

SAVED = ("robot_time_s", "base_path_m", "trips")
POOLED = "all setups"


def trips_of(row: dict[str, Any]) -> int:
    """How many trips a trial made (its `trips` column; one per item without it)."""
    value = row.get("trips")
    if isinstance(value, str):
        try:
            value = parse_json(value) if value else []
        except ValueError:
            value = []
    if isinstance(value, list) and value:
        return len(value)
    return len(str(row.get("order") or "").split())


def _value(row: dict[str, Any], measure: str) -> float:
    if measure == "trips":
        return float(trips_of(row))
    try:
        return float(row.get(measure))
    except (TypeError, ValueError):
        return float("nan")


def carry_savings(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per strategy (and backend), per setup and pooled: pairs, the mean carry-1 and
    carry-2 values and the mean saving of each measure, and (pooled) the Wilcoxon test.
    Empty unless the rows hold both carries."""
    from scipy import stats

    pairs: dict[tuple[str, str, str, str], dict[int, dict[str, Any]]] = defaultdict(dict)
    for row in rows:
        name = row.get("strategy_name") or base_name(row["strategy"])
        if name == FIXED_ORDER or str(row.get("success")) != "True":
            continue
        key = (name, row.get("backend") or "", row["setup"], str(row["trial"]))
        pairs[key][int(row.get("carry") or 1)] = row
    groups: dict[tuple[str, str], dict[str, list[tuple[dict, dict]]]] = defaultdict(
        lambda: defaultdict(list))
    for (name, backend, setup, _), by in pairs.items():
        if 1 in by and 2 in by:
            groups[(name, backend)][setup].append((by[1], by[2]))
    out = []
    for (name, backend), by_setup in sorted(groups.items()):
        pooled = [p for setup in sorted(by_setup) for p in by_setup[setup]]
        for setup, group in [*sorted(by_setup.items()), (POOLED, pooled)]:
            entry: dict[str, Any] = {"strategy": name, "backend": backend, "setup": setup,
                                     "pairs": len(group)}
            for measure in SAVED:
                one = np.array([_value(a, measure) for a, _ in group])
                two = np.array([_value(b, measure) for _, b in group])
                entry[f"{measure}_one"] = float(one.mean())
                entry[f"{measure}_two"] = float(two.mean())
                entry[f"{measure}_saved"] = float((one - two).mean())
                if setup == POOLED:
                    differ = np.any(one != two)
                    entry[f"{measure}_p"] = float(stats.wilcoxon(one, two).pvalue) \
                        if differ and len(group) > 1 else None
            out.append(entry)
    return out


def carry_markdown(entries: Sequence[dict[str, Any]]) -> list[str]:
    """The summary's table of what two hands save (nothing without both carries)."""
    if not entries:
        return []
    several = len({e["backend"] for e in entries}) > 1
    lines = ["", "Two hands against one (--carry 2 vs 1, paired by setup and trial; saved = "
                 "carry 1 minus carry 2, the mean over the pairs; p: Wilcoxon signed-rank "
                 "over the pooled pairs):", "",
             "| strategy | setup | pairs | robot time s (1 → 2) | saved s | saved % | "
             "driven path m (1 → 2) | saved m | trips (1 → 2) | p robot time | p path |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for e in entries:
        name = f"{e['strategy']}@{e['backend']}" if several else e["strategy"]
        share = 100 * e["robot_time_s_saved"] / e["robot_time_s_one"] \
            if e["robot_time_s_one"] else float("nan")

        def p(measure: str, entry: dict[str, Any] = e) -> str:
            value = entry.get(f"{measure}_p")
            return "–" if value is None else f"{value:.3g}"

        setup = f"**{e['setup']}**" if e["setup"] == POOLED else e["setup"]
        lines.append(
            f"| {name} | {setup} | {e['pairs']} | {e['robot_time_s_one']:.1f} → "
            f"{e['robot_time_s_two']:.1f} | {e['robot_time_s_saved']:.1f} | {share:.1f} % | "
            f"{e['base_path_m_one']:.2f} → {e['base_path_m_two']:.2f} | "
            f"{e['base_path_m_saved']:.2f} | {e['trips_one']:.1f} → {e['trips_two']:.1f} | "
            f"{p('robot_time_s') if e['setup'] == POOLED else ''} | "
            f"{p('base_path_m') if e['setup'] == POOLED else ''} |")
    return lines
