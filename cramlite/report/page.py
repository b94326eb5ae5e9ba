"""The report page: one HTML file, inline CSS, no script, no network; its pictures are
files in the `report/` folder beside it (relative links)."""

from __future__ import annotations

import html
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from cramlite.bench.labels import base_name
from cramlite.bench.plots import BOX_LEGEND
from cramlite.bench.specs import FIXED_ORDER
from cramlite.bench.summary import MEASURES, percent
from cramlite.errors import UserInputError
from cramlite.report.folder import BenchFolder
from cramlite.report.trials import failure_text, ok, orders, steps, trial_id

MEDIA = "report"  #: folder of the pictures, beside report.html

CSS = """
body{font:14px/1.45 system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;color:#222;
margin:0 auto;max-width:1280px;padding:0 20px 40px}
h1{font-size:24px;margin:18px 0 4px}h2{font-size:20px;margin:32px 0 8px;
border-bottom:2px solid #ddd;padding-bottom:3px}h3{font-size:16px;margin:22px 0 6px}
h4{font-size:14px;margin:14px 0 4px}
nav{background:#f5f5f5;padding:8px 12px;border-radius:6px;margin:10px 0}
nav a{margin-right:12px;white-space:nowrap}
table{border-collapse:collapse;margin:6px 0 12px;font-size:13px}
th,td{border:1px solid #ddd;padding:3px 7px;text-align:left;vertical-align:top}
th{background:#f0f0f0}td.n{text-align:right;font-variant-numeric:tabular-nums}td.s{white-space:nowrap}
tr.fail td{background:#fdecea}
.status{padding:8px 12px;border-radius:6px;margin:8px 0}
.complete{background:#e8f5e9}.incomplete{background:#fff4e5}
.failures{background:#fdecea;border:1px solid #e57373}
.note{color:#555;font-size:13px}.bad{color:#b71c1c}
.chip{display:inline-block;width:11px;height:11px;border-radius:2px;margin-right:5px;
vertical-align:-1px}
img{max-width:100%;height:auto;border:1px solid #eee}
figure{margin:8px 0 16px}figcaption{font-size:12.5px;color:#444;max-width:1000px}
.trial{border:1px solid #ddd;border-radius:6px;padding:4px 14px 10px;margin:14px 0}
.trial.failed{border-color:#e57373}
.cols{display:flex;flex-wrap:wrap;gap:24px}.cols>div{flex:1 1 380px}
.order{font-family:ui-monospace,Menlo,Consolas,monospace;font-size:12.5px}
details>summary{cursor:pointer;color:#1a5fb4}
.failure{background:#fdecea;border-left:4px solid #d62728;padding:4px 10px;margin:6px 0;
font-size:13px;word-break:break-word}
"""


@dataclass
class PageData:
    """Everything the page shows; pictures are file names in MEDIA ("" when absent)."""

    folder: BenchFolder
    summary: list[dict[str, Any]]
    tests: list[dict[str, Any]]
    percentiles: list[dict[str, Any]]
    colours: dict[str, str]
    baseline_orders: dict[str, Sequence[str]]
    plots: list[tuple[str, str]] = field(default_factory=list)  #: (file, caption)
    all_orders_plot: str = ""
    maps: dict[str, str] = field(default_factory=dict)  #: setup -> file
    map_notes: dict[str, str] = field(default_factory=dict)
    interest: list[dict[str, Any]] = field(default_factory=list)
    failed_left_out: int = 0
    timelines: dict[str, str] = field(default_factory=dict)  #: trial id -> file
    replays: dict[str, str] = field(default_factory=dict)  #: trial id -> file
    replay_notes: dict[str, str] = field(default_factory=dict)
    figures_note: str = ""  #: why there are no pictures ("" when there are)
    #: The backends side by side (`cramlite.bench.agreement`; empty for one backend).
    agreement: list[dict[str, Any]] = field(default_factory=list)
    #: Failures injected (`bench --inject`), per strategy (`cramlite.bench.agreement`).
    injection: list[dict[str, Any]] = field(default_factory=list)
    #: Two hands against one (`bench --carry 1,2`; `cramlite.bench.carrying`).
    carrying: list[dict[str, Any]] = field(default_factory=list)


def e(value: Any) -> str:
    return html.escape(str(value), quote=True)


def num(value: Any, digits: int = 2) -> str:
    try:
        number = float(value)
    except (TypeError, ValueError):
        return "–"
    return "–" if not math.isfinite(number) else f"{number:.{digits}f}"


def img(file: str, alt: str) -> str:
    """A picture of the media folder, linked to itself (click: full size)."""
    src = f"{MEDIA}/{e(file)}"
    return f'<a href="{src}"><img src="{src}" alt="{e(alt)}" loading="lazy"></a>'


def chip(colour: str) -> str:
    return f'<span class="chip" style="background:{e(colour)}"></span>'


def order_html(order: str) -> str:
    names = order.split()
    if not names:
        return '<span class="note">no item fetched</span>'
    return '<span class="order">' + " → ".join(f"{k}&nbsp;{e(n)}" for k, n in
                                              enumerate(names, 1)) + "</span>"


def render_page(data: PageData) -> str:
    folder = data.folder
    setups = folder.setup_names
    parts = [f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
             f"<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
             f"<title>cramlite bench report: {e(folder.path.name)}</title>"
             f"<style>{CSS}</style></head><body>",
             f"<h1>Bench report: {e(folder.path.name)}</h1>", _status(data)]
    links = [("run", "Run"), ("summary", "Summary"), ("tests", "Tests"), ("plots", "Plots")]
    links += [(f"setup-{s}", f"Setup {s}") for s in setups]
    if data.percentiles or data.all_orders_plot:
        links.append(("all-orders", "All orders"))
    links.append(("failures", "Failures"))
    parts.append("<nav>" + "".join(f'<a href="#{e(a)}">{e(t)}</a>' for a, t in links)
                 + "</nav>")
    if data.agreement:
        links.insert(2, ("backends", "Backends"))
    if data.carrying:
        links.insert(2, ("two-hands", "Two hands"))
    parts[-1:] = ["<nav>" + "".join(f'<a href="#{e(a)}">{e(t)}</a>' for a, t in links)
                  + "</nav>"]
    parts += [_run(folder), _summary(data), _carrying(data), _agreement(data),
              _injection(data), _tests(data), _plots(data)]
    parts += [_setup(data, s) for s in setups]
    parts += [_all_orders(data), _failures(data), "</body></html>\n"]
    return "\n".join(p for p in parts if p)


def rerun_command(row: dict[str, Any], setup: Any = None, cwd: str | None = None) -> str:
    """The `cramlite run` command that reruns a trial alone: the setup by its shipped name
    or its file's path, the plan, strategy, order, seed and backend as the bench had them
    (a plan or strategy file given by a relative path: made absolute from `cwd`, the
    folder the bench ran in, so that the command runs from anywhere)."""
    import shlex

    from cramlite.world.setup import resolve_setup_path

    reference = row["setup"]
    if setup is not None:
        try:
            shipped = resolve_setup_path(setup.name).resolve() == setup.source.resolve()
        except UserInputError:
            shipped = False
        reference = setup.name if shipped else str(setup.source)
    strategy = _from_anywhere(row.get("strategy_name", row["strategy"]), cwd)
    words = ["cramlite", "run", reference]
    if row.get("plan") and row["plan"] != "set-table":
        words += ["--plan", _from_anywhere(row["plan"], cwd)]
    words += ["--strategy", strategy if strategy != FIXED_ORDER else "baseline"]
    if strategy == FIXED_ORDER and row.get("given_order"):
        words += ["--order", ",".join(str(row["given_order"]).split())]
    words += ["--seed", str(row.get("seed", 0))]
    if row.get("backend"):
        words += ["--backend", row["backend"]]
    if row.get("inject"):
        words += ["--inject", row["inject"]]
    if str(row.get("carry") or 1) != "1":
        words += ["--carry", str(row["carry"])]
    return shlex.join(words)


def _from_anywhere(reference: str, cwd: str | None) -> str:
    """A `path/to/file.py:name` reference with a relative path made absolute from `cwd`;
    anything else (a name, a module, an absolute path) as it is."""
    from pathlib import Path

    from cramlite.plugins import names_file

    if not cwd or not names_file(reference):
        return reference
    path, _, name = reference.rpartition(":")
    if Path(path).expanduser().is_absolute():
        return reference
    return f"{Path(cwd) / path}:{name}"


def _status(data: PageData) -> str:
    folder = data.folder
    rows = folder.rows
    failed = sum(not ok(r) for r in rows)
    counts = f"{len(rows)} trial{'s' * (len(rows) != 1)} in trials.csv, {failed} failed"
    if folder.other_batches:  # (the page shows the last bench command's trials)
        counts += (f"; {folder.other_batches} more of earlier bench commands with other "
                   "options are not shown (rerun such a command for its report)")
    if folder.running:
        return (f'<p class="status incomplete">Incomplete: a bench is still writing into this '
                f'folder ({e(folder.running)}); {e(counts)}'
                + (f" ({folder.planned_done} of the {folder.planned} it runs)"
                   if folder.planned else "")
                + ". Run <code>cramlite report DIR</code> again for the rest.</p>")
    if folder.planned is not None and folder.planned_done < folder.planned:
        return (f'<p class="status incomplete">Incomplete: {folder.planned_done} of the '
                f"{folder.planned} trials of the last bench command are here ({e(counts)}); "
                "it was interrupted. Run the same command again to finish, then "
                "<code>cramlite report DIR</code>.</p>")
    if failed:
        return (f'<p class="status failures">Complete, with failures: {e(counts)} (see '
                '<a href="#failures">Failures</a>).</p>')
    return f'<p class="status complete">Complete: {e(counts)}.</p>'


#: Arguments a bench records that are its own bookkeeping, not options a user gave.
INTERNAL_ARGUMENTS = ("command", "backends_list", "inject_text")


def _argument(value: object) -> str:
    """An option's value as a user would write it (None: not given, so the default)."""
    if value is None:
        return "(not given: the default)"
    if isinstance(value, list | tuple):
        return ",".join(str(v) for v in value)
    return str(value)


def _run(folder: BenchFolder) -> str:
    meta = folder.metadata
    arguments = meta.get("arguments") if isinstance(meta.get("arguments"), dict) else {}
    params = "".join(f"<tr><th>{e(k)}</th><td>{e(_argument(v))}</td></tr>"
                     for k, v in arguments.items() if k not in INTERNAL_ARGUMENTS)
    versions = meta.get("versions") if isinstance(meta.get("versions"), dict) else {}
    libs = "".join(f"<tr><th>{e(k)}</th><td>{e(v)}</td></tr>" for k, v in versions.items())
    runs = meta.get("runs") if isinstance(meta.get("runs"), list) else []
    facts = [("bench started", meta.get("written", "–")), ("python", meta.get("python", "–")),
             ("platform", meta.get("platform", "–")), ("executor", meta.get("executor", "–")),
             ("bench commands into this folder", len(runs) or "–")]
    env = "".join(f"<tr><th>{e(k)}</th><td>{e(v)}</td></tr>" for k, v in facts)
    if not meta:
        return ('<h2 id="run">Run</h2><p class="note">No metadata.json in the folder: run '
                "parameters and library versions unknown.</p>")
    return (f'<h2 id="run">Run</h2><div class="cols"><div><h4>Parameters (last bench '
            f"command)</h4><table>{params}</table></div><div><h4>Library versions</h4>"
            f"<table>{libs}</table><table>{env}</table></div></div>")


def _summary(data: PageData) -> str:
    head = ("<tr><th>setup</th><th>strategy</th><th>trials</th><th>success</th>"
            "<th>robot time s<br>mean / median</th><th>driving s</th><th>arm s</th>"
            "<th>driven path m<br>mean / median</th><th>straight-line m</th>"
            "<th>edit distance to baseline</th><th>most frequent order</th></tr>")
    body = []
    for entry in data.summary:
        ok_trials = round(entry["success_rate"] * entry["trials"])
        cls = ' class="fail"' if ok_trials < entry["trials"] else ""
        body.append(
            f"<tr{cls}><td><a href=\"#setup-{e(entry['setup'])}\">{e(entry['setup'])}</a></td>"
            f"<td class=s>{chip(data.colours.get(entry['strategy'], '#999'))}"
            f"{e(entry['strategy'])}"
            f"</td><td class=n>{entry['trials']}</td>"
            f"<td class=n>{ok_trials}/{entry['trials']} ({entry['success_rate']:.0%})</td>"
            f"<td class=n>{num(entry['robot_time_s_mean'])} / "
            f"{num(entry['robot_time_s_median'])}</td>"
            f"<td class=n>{num(entry['drive_s_mean'])}</td>"
            f"<td class=n>{num(entry['arm_s_mean'])}</td>"
            f"<td class=n>{num(entry['base_path_m_mean'])} / "
            f"{num(entry['base_path_m_median'])}</td>"
            f"<td class=n>{num(entry['straight_line_m_mean'])}</td>"
            f"<td class=n>{num(entry['edit_vs_baseline'])}</td>"
            f"<td>{order_html(entry['order'])}</td></tr>")
    if not body:
        return '<h2 id="summary">Summary</h2><p class="note">No trials of a strategy yet.</p>'
    return ('<h2 id="summary">Summary</h2><table>' + head + "".join(body) + "</table>"
            '<p class="note">Times, paths and distances are means (and medians) over the '
            "successful trials. Robot time: the robot's own time, from the plan's start to "
            "the end of its last motion (driving and arm motions, less the time both move "
            "at once), deterministic for a seed; the host's time to plan and execute it is "
            "not in it. Driving: base trajectories at up to 1 m/s and 1 rad/s, accelerating "
            "at 1 m/s² and 1.5 rad/s²; arm: arm, torso and gripper motion timed from the "
            "URDF's limits. "
            "Driven path: length of the base paths actually executed; straight-line: sum of "
            "the straight legs robot → item → target. Edit distance: normalised "
            "Damerau-Levenshtein distance of the most frequent order to the setup's baseline "
            "order (0 = the same order, 1 = nothing in common).</p>")


def _agreement(data: PageData) -> str:
    """Where the backends of a bench disagree (orders, success, where items ended)."""
    import math

    from cramlite.bench.agreement import AGREEMENT_TOLERANCE_M

    entries = data.agreement
    if not entries:
        return ""
    pairs = sorted({x["backends"] for x in entries})
    agree = sum(x["agree"] for x in entries)
    gaps = [x["gap_m"] for x in entries if not math.isnan(x["gap_m"])]
    head = (f'<h2 id="backends">Backends side by side</h2><p>'
            f'{"; ".join(f"{e(a)} vs {e(b)}" for a, b in pairs)}: <b>{agree} of '
            f"{len(entries)}</b> trials agree (the same order, the same success, every item "
            f"within {AGREEMENT_TOLERANCE_M * 100:g} cm of where the other left it)"
            + (f"; items at most {max(gaps) * 100:.2f} cm apart." if gaps else ".")
            + "</p>")
    differ = [x for x in entries if not x["agree"]]
    if not differ:
        return head
    rows = "".join(
        f"<tr class=bad><td>{e(x['setup'])}</td><td>{e(x['strategy'])}</td>"
        f"<td class=n>{e(x['trial'])}</td><td>{e(x['backends'][0])} vs {e(x['backends'][1])}"
        f"</td><td>{'same' if x['same_order'] else '<b>differs</b>'}</td>"
        f"<td>{'same' if x['same_success'] else '<b>differs</b>'}</td><td class=n>"
        + ("–" if math.isnan(x["gap_m"]) else
           f"{x['gap_m'] * 100:.2f} cm ({e(x['worst_item'])})") + "</td></tr>"
        for x in differ)
    return (head + "<table><tr><th>setup</th><th>strategy</th><th>trial</th><th>backends"
            "</th><th>order</th><th>success</th><th>largest item gap</th></tr>" + rows
            + "</table>")


def _carrying(data: PageData) -> str:
    """What two hands save against one, per strategy, per setup and pooled."""
    if not data.carrying:
        return ""
    from cramlite.bench.carrying import POOLED

    several = len({x["backend"] for x in data.carrying}) > 1

    def row(x: dict[str, Any]) -> str:
        pooled = x["setup"] == POOLED
        share = 100 * x["robot_time_s_saved"] / x["robot_time_s_one"] \
            if x["robot_time_s_one"] else float("nan")
        name = f"{x['strategy']}@{x['backend']}" if several else x["strategy"]
        cells = [e(name), f"<b>{e(x['setup'])}</b>" if pooled else e(x["setup"]),
                 str(x["pairs"]),
                 f"{num(x['robot_time_s_one'], 1)} → {num(x['robot_time_s_two'], 1)}",
                 num(x["robot_time_s_saved"], 1), f"{num(share, 1)} %",
                 f"{num(x['base_path_m_one'])} → {num(x['base_path_m_two'])}",
                 num(x["base_path_m_saved"]),
                 f"{num(x['trips_one'], 1)} → {num(x['trips_two'], 1)}",
                 _p(x.get("robot_time_s_p")) if pooled else "",
                 _p(x.get("base_path_m_p")) if pooled else ""]
        return "<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>"

    return ('<h2 id="two-hands">Two hands against one</h2><p class="note">Each trial run '
            "with <code>--carry 1</code> and <code>--carry 2</code> is a pair (same setup, "
            "strategy, trial and seed; both successful). Saved = carry 1 minus carry 2, the "
            "mean over the pairs; p: Wilcoxon signed-rank over the pairs pooled over setups "
            "(5 pairs alone cannot go below p = 0.0625).</p><table><tr><th>strategy</th>"
            "<th>setup</th><th>pairs</th><th>robot time s (1 → 2)</th><th>saved s</th>"
            "<th>saved</th><th>driven path m (1 → 2)</th><th>saved m</th><th>trips (1 → 2)"
            "</th><th>p robot time</th><th>p path</th></tr>"
            + "".join(row(x) for x in data.carrying) + "</table>")


def _injection(data: PageData) -> str:
    """What `--inject` did: failures drawn, trials recovered, items lost, per strategy."""
    if not data.injection:
        return ""
    rows = "".join(
        f"<tr><td>{e(x['strategy'])}</td><td>{e(x['inject'])}</td>"
        f"<td class=n>{x['trials']}</td><td>"
        + e(", ".join(f"{k} {n}" for k, n in sorted(x["drawn"].items())) or "none drawn")
        + f"</td><td class=n>{x['recovered']} of {x['with_failures']}</td>"
        f"<td class=\"n{' bad' if x['lost'] else ''}\">{x['lost']}</td></tr>"
        for x in data.injection)
    return ('<h2 id="injected">Injected failures</h2><p class="note">Executions failed on '
            "purpose (<code>--inject</code>, seeded by each trial's seed): recovered = trials "
            "with a failure drawn that still set everything in place.</p><table><tr>"
            "<th>strategy</th><th>inject</th><th>trials</th><th>failures drawn</th>"
            "<th>recovered</th><th>items lost</th></tr>" + rows + "</table>")


def _tests(data: PageData) -> str:
    if not data.tests:
        return ('<h2 id="tests">Statistical tests</h2><p class="note">None: the paired tests '
                "compare each strategy with a reference (<code>bench --reference</code>; "
                "default baseline, else the first strategy), and this folder holds no other "
                "strategy, or no successful pairs.</p>")
    reference = e(base_name(data.tests[0]["reference"]))
    rows = []
    for test in data.tests:
        for measure in MEASURES[1:]:
            t = test.get(measure, {})
            per = t.get("per_setup")
            rows.append(
                f"<tr><td>{e(test['strategy'])} vs {e(test['reference'])}</td>"
                f"<td>{e(measure)}</td><td class=n>{t.get('pairs', test['pairs'])}</td>"
                f"<td class=n>{num(t.get('mean'))}</td><td class=n>"
                f"{num(t.get('reference_mean'))}</td><td class=n>{num(t.get('W'), 1)}</td>"
                f"<td class=n>{_p(t.get('p'))}</td><td>"
                + (f"n={per['n']}, W={num(per['W'], 1)}, p={_p(per['p'])}" if per else
                   e(t.get("note", "–") if t.get("p") is None else "–"))
                + "</td></tr>")
    return ('<h2 id="tests">Statistical tests</h2><p class="note">Wilcoxon signed-rank test '
            f"of each strategy against {reference}, paired by setup and trial (the same "
            "seed), "
            "on the successful pairs; and on the per-setup means (n = number of setups), "
            "as the source compared them. p &lt; 0.05: the difference is unlikely to be "
            "chance.</p><table><tr><th>comparison</th><th>measure</th><th>pairs</th>"
            f"<th>mean</th><th>{reference} mean</th><th>W</th><th>p</th><th>per-setup means"
            "</th></tr>" + "".join(rows) + "</table>")


def _p(value: Any) -> str:
    return "–" if value is None else f"{float(value):.3g}"


def _plots(data: PageData) -> str:
    if data.figures_note:
        return f'<h2 id="plots">Plots</h2><p class="note">{e(data.figures_note)}</p>'
    legend = "; ".join(BOX_LEGEND)
    figures = "".join(f"<figure>{img(f, c)}<figcaption>{e(c)} Successful trials only; "
                      f"{e(legend)}; n above each box: the trials in it.</figcaption></figure>"
                      for f, c in data.plots)
    return f'<h2 id="plots">Plots</h2>{figures}'


def _setup(data: PageData, name: str) -> str:
    folder = data.folder
    setup = folder.setups.get(name)
    rows = [r for r in folder.rows if r["setup"] == name]
    parts = [f'<h2 id="setup-{e(name)}">Setup {e(name)}</h2>']
    if setup is not None and setup.description:
        parts.append(f"<p>{e(setup.description)}</p>")
    if setup is not None:
        baseline_order = " ".join(data.baseline_orders.get(name, ()))
        parts.append(f'<p class="note">Baseline order: {order_html(baseline_order)}</p>')
    note = folder.setup_notes.get(name) or data.map_notes.get(name)
    if note:
        parts.append(f'<p class="note bad">{e(note)}</p>')
    if name in data.maps:
        parts.append(f"<figure>{img(data.maps[name], f'top-down map of {name}')}<figcaption>"
                     "The kitchen from above, one panel per strategy: every trial's driven base "
                     "path (faint), the first trial's in bold with arrows in the direction of "
                     "travel, the numbers at the items the order it fetched them in; red cross: "
                     "an item (or drawer, cupboard) a failed trial could not fetch, place, open "
                     "or close. Items (●) start where their name is, "
                     "targets (□) are where they go.</figcaption></figure>")
    parts.append("<h3>Orders chosen</h3>")
    table = ["<table><tr><th>strategy</th><th>order</th><th>trials</th><th>failed</th>"
             "<th>edit distance to baseline</th></tr>"]
    from cramlite.evaluation.metrics import edit_distance

    baseline = list(data.baseline_orders.get(name, ()))
    for strategy in folder.strategies:
        found = orders(rows, name, strategy)
        if not found:
            table.append(f"<tr><td>{chip(data.colours[strategy])}{e(strategy)}</td>"
                         '<td colspan=4 class="note">no trial yet</td></tr>')
        for order, trials, failed in found:
            edit = edit_distance(order.split(), baseline) if order and baseline else None
            cls = ' class="fail"' if failed else ""
            table.append(f"<tr{cls}><td class=s>{chip(data.colours[strategy])}{e(strategy)}</td>"
                         f"<td>{order_html(order)}</td><td>{e(_ranges(trials))}</td>"
                         f"<td class=n>{failed}</td><td class=n>{num(edit)}</td></tr>")
    parts.append("".join(table) + "</table>")
    fixed = [r for r in rows if r["strategy"] == FIXED_ORDER]
    if fixed:
        parts.append(f'<p class="note">Plus {len(fixed)} fixed-order trials (every order; '
                     f'see <a href="#all-orders">all orders</a>).</p>')
    mine = [r for r in data.interest if r["setup"] == name]
    if mine:
        parts.append("<h3>Trials</h3><p class=\"note\">The first trial of each strategy and "
                     "every failed one: what the robot did when (the task tree's actions over "
                     "robot time), how long each step took, what failed"
                     + (", and the replay." if data.replays else ".") + "</p>")
        parts += [_trial(data, r) for r in mine]
    return "\n".join(parts)


def _ranges(values: Sequence[int]) -> str:
    """[0, 1, 2, 5] -> '0-2, 5'."""
    out, start = [], None
    for k, v in enumerate(values):
        if start is None:
            start = v
        if k + 1 == len(values) or values[k + 1] != v + 1:
            out.append(f"{start}" if start == v else f"{start}-{v}")
            start = None
    return ", ".join(out)


def _trial(data: PageData, row: dict[str, Any]) -> str:
    tid = trial_id(row)
    good = ok(row)
    colour = data.colours.get(row["strategy"], "#999")
    head = (f'<div class="trial{"" if good else " failed"}" id="trial-{e(tid)}"><h4>'
            f"{chip(colour)}{e(row['setup'])} · {e(row['strategy'])} · trial {e(row['trial'])}"
            f" — " + ("succeeded" if good else '<span class="bad">FAILED</span>') + "</h4>")
    cwd = data.folder.metadata.get("cwd")
    rerun = rerun_command(row, data.folder.setups.get(row["setup"]),
                          cwd if isinstance(cwd, str) else None)
    facts = (f"<p>Order: {order_html(row['order'])}<br><span class=note>seed "
             f"{e(row.get('seed', '–'))}; robot time {num(row.get('robot_time_s'))} s "
             f"(driving {num(row.get('drive_s'))} s, arm {num(row.get('arm_s'))} s; opening "
             f"and closing {num(row.get('open_close_s'))} s), computed in "
             f"{num(row.get('wall_s'))} s; driven path {num(row.get('base_path_m'))} m"
             f"{'; on ' + e(row['backend']) if row.get('backend') else ''}. Rerun it alone: "
             f"<code>{e(rerun)}</code></span></p>")
    parts = [head, facts]
    if not good:
        lines = failure_text(row).split(" | ")
        parts.append('<div class="failure">' + "<br>".join(
            e(t if len(t) <= 260 else t[:260] + " …") for t in lines) + "</div>")
    if tid in data.timelines:
        parts.append(img(data.timelines[tid], f"timeline of {tid}"))
    table = _steps(row)
    if table:
        parts.append(f"<details{'' if good else ' open'}><summary>Steps and their durations"
                     f"</summary>{table}</details>")
    if tid in data.replays:
        parts.append(f"<figure>{img(data.replays[tid], f'replay of {tid}')}<figcaption>Replay "
                     f"from the trace, {e(_speed(data.replays[tid]))} times faster than the "
                     "robot moved (robot time and the action in progress at the top left)."
                     "</figcaption></figure>")
    elif tid in data.replay_notes:
        parts.append(f'<p class="note">{e(data.replay_notes[tid])}</p>')
    parts.append("</div>")
    return "\n".join(parts)


def _speed(file: str) -> str:
    return file.rsplit("-x", 1)[-1].removesuffix(".gif")


def _steps(row: dict[str, Any]) -> str:
    found = steps(row.get("actions") or [])
    if not found:
        return ""
    lines = ["<table><tr><th>step</th><th>object</th><th>start s</th><th>duration s</th>"
             "<th>status</th><th>failure</th></tr>"]
    for step in found:
        indent = "&nbsp;" * 6 * step.depth
        times = f" ({step.count} attempts)" if step.count > 1 else ""
        cls = ' class="fail"' if step.status == "failed" else ""
        failure = step.failure if len(step.failure) <= 220 else step.failure[:220] + " …"
        lines.append(f"<tr{cls}><td>{indent}{e(step.name.removesuffix('Action'))}{e(times)}"
                     f"</td><td>{e(step.object)}</td><td class=n>{num(step.start, 1)}</td>"
                     f"<td class=n>{num(step.duration, 1)}</td><td>{e(step.status)}</td>"
                     f'<td title="{e(step.failure)}">{e(failure)}</td></tr>')
    return "".join(lines) + "</table>"


def _all_orders(data: PageData) -> str:
    if not (data.percentiles or data.all_orders_plot):
        return ""
    parts = ['<h2 id="all-orders">All orders</h2><p class="note">Every order of the items was '
             "run once as a fixed order; where each strategy's mean falls among them "
             "(percentage of orders with a lower value: 0 % = better than every order).</p>"]
    if data.all_orders_plot:
        parts.append(f"<figure>{img(data.all_orders_plot, 'strategies among all orders')}"
                     "<figcaption>Histogram: driven path of every fixed order; vertical line: "
                     "each strategy's mean driven path (successful trials).</figcaption>"
                     "</figure>")
    if data.percentiles:
        parts.append("<table><tr><th>setup</th><th>strategy</th><th>orders</th>"
                     "<th>driven path</th><th>straight-line</th><th>robot time</th></tr>")
        for p in data.percentiles:
            parts.append(f"<tr><td>{e(p['setup'])}</td><td>{e(p['strategy'])}</td>"
                         f"<td class=n>{p['orders']}</td>"
                         f"<td class=n>{percent(p['base_path_m_percentile'])}</td>"
                         f"<td class=n>{percent(p['straight_line_m_percentile'])}</td>"
                         f"<td class=n>{percent(p['robot_time_s_percentile'])}</td></tr>")
        parts.append("</table>")
    return "\n".join(parts)


def _failures(data: PageData) -> str:
    failed = [r for r in data.folder.rows if not ok(r)]
    if not failed:
        return '<h2 id="failures">Failures</h2><p>None: every trial succeeded.</p>'
    shown = {trial_id(r) for r in data.interest}
    lines = ['<h2 id="failures">Failures</h2><table><tr><th>setup</th><th>strategy</th>'
             "<th>trial</th><th>what failed</th></tr>"]
    for row in failed:
        tid = trial_id(row)
        link = (f'<a href="#trial-{e(tid)}">{e(row["trial"])}</a>' if tid in shown
                else e(row["trial"]))
        text = failure_text(row)
        lines.append(f"<tr class=fail><td>{e(row['setup'])}</td><td>{e(row['strategy'])}</td>"
                     f"<td>{link}</td><td title=\"{e(text)}\">"
                     f"{e(text if len(text) < 400 else text[:400] + ' …')}</td></tr>")
    lines.append("</table>")
    if data.failed_left_out:
        lines.append(f'<p class="note">{data.failed_left_out} failed trials have no timeline '
                     "of their own here (the first ones of each setup do).</p>")
    return "".join(lines)
