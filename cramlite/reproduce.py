"""`cramlite reproduce`: every table the README claims, rebuilt from scratch, ours beside
the published numbers, on one page (reproduce.md and reproduce.html).

Sections: the OPM's fit on table setting (thesis 3.3.1-3.3.3, Table 3.4); the robot
experiment's orders and edit distances (Tables 4.2-4.4, on the kinematic backend); the
learned models against the OPM on table setting, cooking, clearing up and all activities
(3.3.4-3.3.6, `--protocol thesis`, models trained here on table setting); an ablation of
the learned models' scoring where a figure is off; and parameter recovery.
"""

from __future__ import annotations

import html
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cramlite.errors import UserInputError
from cramlite.evaluation.data import Episode, load_episodes
from cramlite.evaluation.published import PUBLISHED_APE
from cramlite.resources import resolve_data_path

#: Published figures (thesis chapters 3 and 4; ../shared/SPEC.md).
PUBLISHED_ML = PUBLISHED_APE
TABLE_4_2 = {"v1": "breakfast-cereal cup bowl spoon milk",
             "v2": "spoon breakfast-cereal milk cup bowl",
             "v3": "cup milk breakfast-cereal bowl spoon",
             "v4": "bowl milk cup spoon breakfast-cereal",
             "v5": "bowl cup breakfast-cereal spoon milk"}
TABLE_4_3 = {"v1": "bowl breakfast-cereal cup spoon milk",
             "v2": "bowl cup milk breakfast-cereal spoon",
             "v3": "bowl spoon breakfast-cereal cup milk",
             "v4": "bowl spoon milk cup breakfast-cereal",
             "v5": "bowl milk breakfast-cereal spoon cup"}
TABLE_4_4 = {"v1": 0.4, "v2": 0.8, "v3": 0.8, "v4": 0.4, "v5": 0.4}
#: How far a figure may be from the published one and still count as reproduced.
TOLERANCE = 0.6
MODELS = ("rnn", "nn", "cpt")
ACTIVITIES = ("table-setting", "cooking", "clearing-up", "all")


@dataclass
class Section:
    title: str
    intro: str
    header: list[str]
    rows: list[list[str]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


@dataclass
class Options:
    out: Path
    episodes: int | None = None  #: at most this many episodes per data set (tests)
    setups: Sequence[str] = ("v1", "v2", "v3", "v4", "v5")
    epochs: int = 300
    recovery_sets: int = 20
    recovery_seeds: int = 3
    repeats: int = 100
    seed: int = 0


def _data(name: str, limit: int | None) -> list[Episode]:
    episodes, _ = load_episodes(resolve_data_path(name))
    return episodes[:limit] if limit else episodes


def _f(value: float | None, digits: int = 2) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def fit_section(options: Options) -> Section:
    from cramlite.evaluation.evaluate import evaluate
    from cramlite.evaluation.fit import fit

    episodes = _data("table-setting", options.episodes)
    result = fit(episodes, "opm", ("xy", "xyz"), "ape", options.repeats, options.seed)
    dims, index = result.best()
    best = result.params(index)
    plateau = {k: v for k, v in result.tied_best(dims).items() if v[1] > v[0]}
    section = Section("The OPM on table setting (thesis 3.3.1-3.3.3, Table 3.4)",
                      f"{len(episodes)} episodes, xy unless said, {options.repeats} "
                      f"repeats, seed {options.seed}, protocol heldout.",
                      ["figure", "thesis", "cramlite", "reproduced"])

    def score(strategy: str, params: dict[str, float], metric: str) -> float:
        return float(np.mean(evaluate(episodes, strategy, params, metric=metric,
                                      repeats=options.repeats, seed=options.seed).scores))

    source = {"strong_k": 0.2, "mid_k": 0.3, "food_k": 1.2, "c": 1.7}
    ape = score("opm", source, "ape")
    section.rows.append(["OPM APE, source parameters (0.2/0.3/1.2/1.7)", "4.04", _f(ape),
                         _verdict(ape, 4.04)])
    section.rows.append(["best fit (strong k / mid k / food k / c)", "0.2 / 0.3 / 1.2 / 1.7",
                         " / ".join(f"{best[k]:.1f}" for k in best) + f" ({dims})",
                         "yes" if abs(best["strong_k"] - 0.2) < 0.11 and
                         abs(best["mid_k"] - 0.3) < 0.11 else "no"])
    section.rows.append(["best fit's APE", "4.04", _f(float(result.means(dims)[index])), ""])
    edit = {**source, "c": 1.4}
    for label, strategy, published in (("OPM edit distance, c = 1.4", "opm", 0.369),
                                       ("2-step edit distance, c = 1.4", "opm-2step", 0.378)):
        value = score(strategy, edit, "edit")
        section.rows.append([label, f"{published:.3f}", _f(value, 3),
                             _verdict(value, published, 0.05)])
    if plateau:
        section.notes.append("The fit is a plateau in " + ", ".join(
            f"{k} ({lo:.1f}-{hi:.1f})" for k, (lo, hi) in plateau.items()) +
            ": any value there fits exactly as well (it changes no decision in these "
            "episodes); the best is the plateau's middle.")
    section.notes.append("The thesis's edit distances are not reproduced by these data or "
                         "by the published code (docs/evaluation.md); APE is.")
    return section


def robot_section(options: Options) -> Section:
    from cramlite.evaluation.metrics import edit_distance
    from cramlite.trial import TrialRunner

    section = Section("The robot experiment (Tables 4.2-4.4)",
                      f"One trial per setup and strategy on the kinematic backend, seed "
                      f"{options.seed}.",
                      ["setup", "baseline (Table 4.2)", "ours", "OPM (Table 4.3)", "ours",
                       "edit (Table 4.4)", "ours", "robot time OPM / baseline"])
    for setup in options.setups:
        with TrialRunner(setup, backend="kinematic") as runner:
            base = runner.run("baseline", seed=options.seed)
            opm = runner.run("opm", seed=options.seed)
        ours_base, ours_opm = " ".join(base.order), " ".join(opm.order)
        edit = edit_distance(base.order, opm.order)
        published_edit = TABLE_4_4.get(setup)
        section.rows.append([
            setup, TABLE_4_2.get(setup, "-"),
            _same(ours_base, TABLE_4_2.get(setup)) + ("" if base.success else " (failed)"),
            TABLE_4_3.get(setup, "-"),
            _same(ours_opm, TABLE_4_3.get(setup)) + ("" if opm.success else " (failed)"),
            _f(published_edit, 1), _f(edit, 1),
            f"{opm.robot_time_s:.1f} / {base.robot_time_s:.1f} s"])
    section.notes.append("Published robot times (379.69 s OPM, 385.03 s baseline) came from "
                         "PyCRAM with ROS and are not comparable: ours is the simulated "
                         "robot's own time within the PR2's limits.")
    return section


def train_models(options: Options, folder: Path) -> dict[str, str]:
    from cramlite.learning.train import train_model

    folder.mkdir(parents=True, exist_ok=True)
    paths = {}
    for kind in MODELS:
        path = folder / f"{kind}.model"
        train_model(resolve_data_path("table-setting"), kind, path, seed=options.seed,
                    epochs=options.epochs)
        paths[kind] = str(path)
    return paths


def ml_section(options: Options, models: dict[str, str]) -> Section:
    from cramlite.learning.compare import compare

    section = Section("Learned models against the OPM (thesis 3.3.4-3.3.6, Table 3.8)",
                      "APE means, `--protocol thesis`; the models are trained here on "
                      "table setting (seed "
                      f"{options.seed}); p: paired Wilcoxon test against the OPM.",
                      ["activity", "episodes", "model", "thesis", "cramlite", "p vs OPM",
                       "within 0.6"])
    names = ["opm", *(f"learned:{models[k]}" for k in MODELS)]
    for activity in ACTIVITIES:
        episodes = _data(activity, options.episodes)
        result = compare(episodes, names, protocol="thesis", repeats=options.repeats,
                         seed=options.seed)["summary"]
        for label, name in zip(("opm", *MODELS), names, strict=True):
            ours = result["strategies"][name]["mean"]
            published = PUBLISHED_ML[activity].get(label)
            test = result["wilcoxon_vs_first"].get(name)
            section.rows.append([activity, str(result["episodes"]), label.upper(),
                                 _f(published), _f(ours),
                                 "-" if test is None else f"{test['p']:.2g}",
                                 "-" if published is None else _verdict(ours, published)])
    section.notes.append("An item a model never saw (none of clearing up's, two in five of "
                         "cooking's) cannot be its output: a step that takes one is an "
                         "error. The thesis left the CPT out of the generalisation tests.")
    return section


def ablation_section(options: Options, models: dict[str, str]) -> Section:
    from cramlite.evaluation.evaluate import episode_rng
    from cramlite.learning.modelfile import load_model
    from cramlite.learning.scoring import thesis_ape, unseen_steps

    nn, rnn = load_model(models["nn"]), load_model(models["rnn"])
    variants: list[tuple[str, Callable[[Episode, int], float]]] = [
        ("NN, n-1 positions (the protocol)", lambda e, i: thesis_ape(nn, e, 1, None)),
        ("NN, every position (n)", lambda e, i: thesis_ape(nn, e, 1, None, positions="n")),
        ("RNN, the protocol (sampled, primed by the last known item)",
         lambda e, i: thesis_ape(rnn, e, options.repeats, episode_rng(options.seed, i))),
        ("RNN, primed by the start token after an unseen item",
         lambda e, i: thesis_ape(rnn, e, options.repeats, episode_rng(options.seed, i),
                                 unseen_prime="start")),
        ("RNN, its most likely item (argmax)",
         lambda e, i: thesis_ape(rnn, e, options.repeats, episode_rng(options.seed, i),
                                 choice="argmax")),
        ("RNN, every position (n)",
         lambda e, i: thesis_ape(rnn, e, options.repeats, episode_rng(options.seed, i),
                                 positions="n")),
        ("floor: steps taking an unseen item (n-1)", lambda e, i: unseen_steps(nn, e)),
        ("floor: steps taking an unseen item (n)", lambda e, i: unseen_steps(nn, e, "n")),
    ]
    activities = ACTIVITIES[:3]
    section = Section("Ablation: what the learned models' figures depend on",
                      "APE means of our models under variants of the thesis protocol, "
                      "beside the published figure (NN / RNN).",
                      ["variant", *activities])
    data = {a: _data(a, options.episodes) for a in activities}
    section.rows.append(["published NN / RNN",
                         *(f"{PUBLISHED_ML[a]['nn']:.2f} / {PUBLISHED_ML[a]['rnn']:.2f}"
                           for a in activities)])
    for label, score in variants:
        section.rows.append([label, *(_f(float(np.mean([score(e, i) for i, e in
                                                         enumerate(data[a])])))
                                      for a in activities)])
    section.notes += [
        "(Measured on the full data, seed 0.) No variant brings the NN's cooking figure "
        "to the published 4.96, which is above "
        "the 4.18 positions the APE scores per cooking episode: the published NN must "
        "have scored every position (n = 5.18) and erred on 96 % of them, while 60 % of "
        "cooking's steps take an item table setting has. Scored on every position our NN "
        "errs on the unseen items only and on some of the known ones (3.83). Its figure "
        "on clearing up, where no item is known, is reproduced that way (7.59 vs 7.41).",
        "The RNN errs on nearly every cooking step with a known item (4.09, floor 1.84); "
        "the published 3.42 needs it right on a third of them. Priming and picking do "
        "not explain the difference (4.03-4.09). Training seeds move the figures by "
        "0.05 at most (seeds 0-2). The thesis's implementation is not published, so the "
        "rest of the gap stays unattributed; the OPM is best on both activities either "
        "way, as published.",
    ]
    return section


def recovery_section(options: Options) -> Section:
    from cramlite.evaluation.recovery import (
        EPISODES_PER_TASK,
        RECOVERY_TEMPERATURE,
        recovery_study,
        recovery_table,
    )

    like = _data("table-setting", options.episodes)
    runs = recovery_study(like, options.recovery_sets, options.recovery_seeds)
    section = Section("Parameter recovery (OPM on the table-setting tasks)",
                      f"{options.recovery_sets} generating sets from the Table 3.4 grid x "
                      f"{options.recovery_seeds} seeds, {EPISODES_PER_TASK * len(like)} "
                      f"simulated episodes each, softmax temperature {RECOVERY_TEMPERATURE}, "
                      "fitted by maximum likelihood under that softmax (`fit --metric "
                      "likelihood`, xy).",
                      ["parameter", "recovered within 0.1", "plateau holds the truth",
                       "mean plateau width"])
    for row in recovery_table(runs):
        section.rows.append([str(row["parameter"]), f"{100 * row['recovered']:.0f} %",
                             f"{100 * row['on_plateau']:.0f} %",
                             f"{row['plateau_width']:.2f}"])
    section.notes.append("Fitted by the thesis's criterion instead (expected APE), food k "
                         "is not identifiable on these tasks: food items are offered in 5 "
                         "of 186, and there values 0.6 apart on average change no choice "
                         "of the model, so the APE cannot tell them apart (a plateau that "
                         "holds the truth). The likelihood also weighs how much likelier "
                         "the choice made was than the others.")
    return section


def _verdict(ours: float | None, published: float, tolerance: float = TOLERANCE) -> str:
    if ours is None:
        return "-"
    return "yes" if abs(ours - published) <= tolerance else f"no ({ours - published:+.2f})"


def _same(ours: str, published: str | None) -> str:
    if published is None:
        return ours
    return "same" if ours == published else ours


def reproduce(options: Options, say: Callable[[str], None] = print) -> list[Section]:
    """Every section, in order (each names how long it took)."""
    options.out.mkdir(parents=True, exist_ok=True)
    sections: list[Section] = []

    def timed(label: str, build: Callable[[], Section | None]) -> None:
        started = time.perf_counter()
        say(f"{label} ...")
        section = build()
        if section is not None:
            section.notes.append(f"Built in {time.perf_counter() - started:.0f} s.")
            sections.append(section)

    timed("fit on table setting", lambda: fit_section(options))
    timed(f"robot experiment {', '.join(options.setups)}", lambda: robot_section(options))
    models: dict[str, str] = {}
    try:
        timed("training the RNN, NN and CPT",
              lambda: models.update(train_models(options, options.out / "models")))
    except UserInputError as exc:  # the learn extra is missing
        sections.append(Section("Learned models", f"Not rebuilt: {exc}", []))
    if models:
        timed("learned models on four activities", lambda: ml_section(options, models))
        timed("ablation", lambda: ablation_section(options, models))
    timed("parameter recovery", lambda: recovery_section(options))
    return sections


def markdown(sections: Sequence[Section]) -> str:
    lines = ["# cramlite reproduce: ours beside the published figures", ""]
    for s in sections:
        lines += [f"## {s.title}", "", s.intro, ""]
        if s.header:
            lines += ["| " + " | ".join(s.header) + " |",
                      "|" + "---|" * len(s.header)]
            lines += ["| " + " | ".join(row) + " |" for row in s.rows]
            lines.append("")
        lines += [f"- {n}" for n in s.notes] + [""]
    return "\n".join(lines)


def html_page(sections: Sequence[Section]) -> str:
    e = html.escape
    parts = ["<!doctype html><html><head><meta charset='utf-8'><title>cramlite reproduce"
             "</title><style>body{font-family:sans-serif;max-width:1100px;margin:2em auto}"
             "table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;"
             "padding:3px 8px;text-align:left}th{background:#f2f2f2}</style></head><body>",
             "<h1>cramlite reproduce: ours beside the published figures</h1>"]
    for s in sections:
        parts += [f"<h2>{e(s.title)}</h2>", f"<p>{e(s.intro)}</p>"]
        if s.header:
            parts.append("<table><tr>" + "".join(f"<th>{e(h)}</th>" for h in s.header)
                         + "</tr>")
            parts += ["<tr>" + "".join(f"<td>{e(c)}</td>" for c in row) + "</tr>"
                      for row in s.rows]
            parts.append("</table>")
        if s.notes:
            parts.append("<ul>" + "".join(f"<li>{e(n)}</li>" for n in s.notes) + "</ul>")
    parts.append("</body></html>")
    return "\n".join(parts)


def write_page(sections: Sequence[Section], out: Path) -> tuple[Path, Path]:
    md, page = out / "reproduce.md", out / "reproduce.html"
    md.write_text(markdown(sections), encoding="utf-8")
    page.write_text(html_page(sections), encoding="utf-8")
    return md, page
