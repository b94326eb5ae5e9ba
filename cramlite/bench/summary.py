"""Batch summary: per setup and strategy, and paired tests of each strategy against a
reference (baseline by default; scipy).

Columns: trials, success rate, robot time (the robot's own time: driving and arm motion,
from the executed trajectories), mean/median wall time (the host's computing), driven
base path, straight-line legs, driving and arm time, the most frequent fetch order and
its normalised edit distance to the setup's baseline order.
"""

from __future__ import annotations

import csv
import json
import statistics
from collections import Counter, defaultdict
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from cramlite.bench.labels import base_name, variant
from cramlite.bench.specs import FIXED_ORDER
from cramlite.evaluation.metrics import edit_distance

MEASURES = ("wall_s", "robot_time_s", "base_path_m", "straight_line_m", "drive_s", "arm_s",
            "open_close_s")


def _float(value: Any) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return float("nan")


def _ok(row: dict[str, Any]) -> bool:
    return str(row.get("success")) == "True"


def summarise(rows: Sequence[dict[str, Any]], baseline_orders: dict[str, Sequence[str]],
              ) -> list[dict[str, Any]]:
    groups: dict[tuple[str, str], list[dict[str, Any]]] = defaultdict(list)
    for row in rows:
        if row["strategy"] != FIXED_ORDER:
            groups[(row["setup"], row["strategy"])].append(row)
    out = []
    for (setup, strategy), group in sorted(groups.items()):
        entry: dict[str, Any] = {"setup": setup, "strategy": strategy, "trials": len(group),
                                 "success_rate": sum(map(_ok, group)) / len(group)}
        for measure in MEASURES:
            values = [_float(r.get(measure)) for r in group if _ok(r)]
            values = [v for v in values if np.isfinite(v)]
            entry[f"{measure}_mean"] = float(np.mean(values)) if values else float("nan")
            entry[f"{measure}_median"] = float(np.median(values)) if values else float("nan")
        orders = Counter(r["order"] for r in group if r["order"])
        order = orders.most_common(1)[0][0] if orders else ""
        entry["order"] = order
        baseline = baseline_orders.get(setup)
        entry["edit_vs_baseline"] = (edit_distance(order.split(), list(baseline))
                                     if order and baseline else float("nan"))
        out.append(entry)
    return out


def default_reference(strategies: Sequence[str]) -> str:
    """The reference when none is asked for: baseline if it runs, else the first strategy
    *as asked* (not the first whose trials happen to finish first)."""
    return "baseline" if "baseline" in strategies else strategies[0]


def reference_strategy(rows: Sequence[dict[str, Any]], asked: str | None = None) -> str:
    """The strategy the paired tests compare with: the one asked for (`bench --reference`),
    else baseline if there are baseline trials, else the first strategy of the rows."""
    names = list(dict.fromkeys(base_name(r["strategy"]) for r in rows
                               if r["strategy"] != FIXED_ORDER))
    if asked:
        return asked
    return "baseline" if "baseline" in names or not names else names[0]


def reference_tests(rows: Sequence[dict[str, Any]], reference: str | None = None,
                    ) -> list[dict[str, Any]]:
    """The paired tests of every strategy against the reference (see `reference_strategy`;
    on each backend and carry: `opm×2@kinematic` against `baseline×2@kinematic`)."""
    reference = reference_strategy(rows, reference)
    labels = sorted({r["strategy"] for r in rows} - {FIXED_ORDER})
    out = []
    for ref in (s for s in labels if base_name(s) == reference):
        out += [paired_tests(rows, s, ref) for s in labels
                if base_name(s) != reference and variant(s) == variant(ref)]
    return out


def paired_tests(rows: Sequence[dict[str, Any]], strategy: str, reference: str = "baseline",
                 ) -> dict[str, Any]:
    """Wilcoxon signed-rank of `strategy` vs `reference`, paired by (setup, trial), on each
    measure; and on per-setup means (n = number of setups), as the source compared."""
    from scipy import stats

    by_key = {(r["setup"], r["trial"], r["strategy"]): r for r in rows if _ok(r)}
    pairs = [(by_key[(s, t, strategy)], by_key[(s, t, reference)])
             for (s, t, name) in by_key if name == strategy and (s, t, reference) in by_key]
    result: dict[str, Any] = {"strategy": strategy, "reference": reference, "pairs": len(pairs)}
    for measure in MEASURES[1:]:
        # (the pairs where both have the measure: a user's plan may not report its legs)
        measured = [(x, y) for x, y in pairs if np.isfinite(_float(x.get(measure)))
                    and np.isfinite(_float(y.get(measure)))]
        a = np.array([_float(x.get(measure)) for x, _ in measured])
        b = np.array([_float(y.get(measure)) for _, y in measured])
        test: dict[str, Any] = {"mean": float(a.mean()) if len(a) else None,
                                "reference_mean": float(b.mean()) if len(b) else None}
        if len(measured) < len(pairs):
            test["pairs"] = len(measured)
        if len(a) and np.any(a != b):
            res = stats.wilcoxon(a, b)
            test.update(W=float(res.statistic), p=float(res.pvalue))
        elif pairs and not measured:
            test.update(W=None, p=None, note="not reported (a user's plan's legs)")
        else:
            test.update(W=None, p=None, note="no pairs or no differences")
        setups = sorted({x["setup"] for x, _ in measured})
        if len(setups) >= 2:
            ma = [np.mean([_float(x.get(measure)) for x, _ in measured if x["setup"] == s])
                  for s in setups]
            mb = [np.mean([_float(y.get(measure)) for _, y in measured if y["setup"] == s])
                  for s in setups]
            if np.any(np.array(ma) != np.array(mb)):
                res = stats.wilcoxon(ma, mb)
                test["per_setup"] = {"n": len(setups), "W": float(res.statistic),
                                     "p": float(res.pvalue)}
        result[measure] = test
    return result


def order_percentiles(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """With all orders run: where each strategy's mean path and time fall among them."""
    out = []
    setups = sorted({r["setup"] for r in rows if r["strategy"] == FIXED_ORDER})
    for setup in setups:
        every = [r for r in rows if r["setup"] == setup and r["strategy"] == FIXED_ORDER
                 and _ok(r)]
        for strategy in sorted({r["strategy"] for r in rows if r["setup"] == setup} -
                               {FIXED_ORDER}):
            mine = [r for r in rows if r["setup"] == setup and r["strategy"] == strategy
                    and _ok(r)]
            if not mine or not every:
                continue
            entry = {"setup": setup, "strategy": strategy, "orders": len(every)}
            for measure in ("base_path_m", "robot_time_s", "straight_line_m"):
                # (of the trials that have the measure, as `summarise` takes them)
                values = [v for v in (_float(r[measure]) for r in mine) if np.isfinite(v)]
                population = np.array([_float(r[measure]) for r in every])
                population = population[np.isfinite(population)]
                if not len(population) or not values:
                    entry[f"{measure}_percentile"] = None  # (not reported)
                    continue
                value = statistics.mean(values)
                entry[f"{measure}_percentile"] = float((population < value).mean() * 100)
            out.append(entry)
    return out


def percent(value: float | None) -> str:
    """A percentile as text ("–": not measured, e.g. legs a user's plan did not report)."""
    return "–" if value is None else f"{value:.0f} %"


def write_summary(folder: Path, summary: list[dict[str, Any]], tests: list[dict[str, Any]],
                  percentiles: list[dict[str, Any]],
                  agreement: Sequence[dict[str, Any]] = (),
                  injection: Sequence[dict[str, Any]] = (),
                  carrying: Sequence[dict[str, Any]] = ()) -> str:
    """summary.csv and summary.md; returns the Markdown (also printed). `agreement`: the
    backends side by side (`cramlite.bench.agreement`), when the bench ran on several."""
    if summary:
        with (folder / "summary.csv").open("w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=list(summary[0]))
            writer.writeheader()
            writer.writerows(summary)
    lines = ["| setup | strategy | trials | success | wall s (mean/median) | robot time s | "
             "driving s | arm s | open/close s | driven path m | straight-line m | "
             "edit vs baseline | order |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]

    def two(value: float) -> str:  # (no successful trial: nothing to measure)
        return f"{value:.2f}" if np.isfinite(value) else "–"

    for e in summary:
        e = {k: two(v) if isinstance(v, float) and k != "success_rate" else v
             for k, v in e.items()}
        lines.append(
            f"| {e['setup']} | {e['strategy']} | {e['trials']} | {e['success_rate']:.0%} | "
            f"{e['wall_s_mean']} / {e['wall_s_median']} | "
            f"{e['robot_time_s_mean']} / {e['robot_time_s_median']} | "
            f"{e['drive_s_mean']} | {e['arm_s_mean']} | "
            f"{e['open_close_s_mean']} | "
            f"{e['base_path_m_mean']} / {e['base_path_m_median']} | "
            f"{e['straight_line_m_mean']} / {e['straight_line_m_median']} | "
            f"{e['edit_vs_baseline']} | {e['order']} |")
    lines.append("")
    lines.append("Driven path: length of the base paths actually executed. Straight-line: sum "
                 "over steps of the xy distances robot -> item -> where it was put. Robot time: "
                 "the robot's own time, from the plan's start to the end of its last motion "
                 "(base trajectories at up to 1 m/s and 1 rad/s, accelerating at 1 m/s^2 and "
                 "1.5 rad/s^2; arm, torso and gripper trajectories timed from the URDF's "
                 "limits), deterministic for a seed; "
                 "wall: the host's time to plan and execute it. open/close: the part of the "
                 "robot time spent opening and closing drawers and doors. Times and lengths "
                 "are of the successful trials (–: none succeeded, or, straight-line, a user's "
                 "plan did not report its legs).")
    from cramlite.bench.agreement import agreement_markdown, injection_markdown

    lines += agreement_markdown(agreement)
    lines += injection_markdown(injection)
    from cramlite.bench.carrying import carry_markdown

    lines += carry_markdown(carrying)
    for test in tests:
        lines += ["", f"Wilcoxon signed-rank, {test['strategy']} vs {test['reference']} "
                      f"({test['pairs']} pairs by setup and trial):"]
        for measure in MEASURES[1:]:
            t = test.get(measure, {})
            if t.get("p") is None:
                lines.append(f"- {measure}: {t.get('note', 'n/a')}")
                continue
            if "pairs" in t:  # (fewer: the others lack the measure)
                measure = f"{measure} ({t['pairs']} pairs)"
            per = t.get("per_setup")
            per_text = (f"; per-setup means (n={per['n']}): W = {per['W']:.1f}, "
                        f"p = {per['p']:.3g}") if per else ""
            lines.append(f"- {measure}: mean {t['mean']:.2f} vs {t['reference_mean']:.2f}, "
                         f"W = {t['W']:.1f}, p = {t['p']:.3g}{per_text}")
    if percentiles:
        lines += ["", "Among all fixed orders (percentage of orders with a lower value; "
                      "0 % = best):"]
        for e in percentiles:
            lines.append(f"- {e['setup']} {e['strategy']}: driven path "
                         f"{percent(e['base_path_m_percentile'])}, straight-line "
                         f"{percent(e['straight_line_m_percentile'])}, robot time "
                         f"{percent(e['robot_time_s_percentile'])} of {e['orders']} orders")
    text = "\n".join(lines) + "\n"
    (folder / "summary.md").write_text(text, encoding="utf-8")
    (folder / "tests.json").write_text(json.dumps({"wilcoxon": tests,
                                                   "all_orders": percentiles}, indent=2))
    return text
