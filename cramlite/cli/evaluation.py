"""`cramlite evaluate`, `cramlite fit` and `cramlite simulate`: strategies against human
sequences, and synthetic sequences drawn from a strategy."""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
from collections.abc import Iterator
from pathlib import Path

from cramlite.cli.common import (
    EXIT_OK,
    episodes_int,
    float_in_range,
    parse_params,
    progress_bar,
    repeats_int,
    seed_int,
    strategy_checked,
    workers_int,
    writable_file,
    writable_folder,
)
from cramlite.errors import UserInputError
from cramlite.evaluation.options import (
    DEFAULT_TEMPERATURE,
    DIM_NAMES,
    FIT_METRICS,
    METRICS,
    PROTOCOLS,
)
from cramlite.strategies.base import StrategyError


@contextlib.contextmanager
def quiet_broken_pipe() -> Iterator[None]:
    """Output into a pipe that was closed (`... --json | head`) ends quietly."""
    try:
        yield
        sys.stdout.flush()
    except BrokenPipeError:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # the interpreter's last flush goes nowhere


def _load_episodes(args: argparse.Namespace):
    from cramlite.evaluation.data import load_episodes
    from cramlite.resources import resolve_data_path

    args.data = str(resolve_data_path(args.data))
    episodes, bad = load_episodes(args.data, on_bad_row=args.on_bad_row)
    for row in bad:
        print(f"cramlite {args.command}: skipped {args.data}: {row}", file=sys.stderr)
    if not episodes:
        raise UserInputError("no usable episodes", source=args.data)
    return episodes, bad




def _sha256(args: argparse.Namespace) -> str | None:
    """The data file's hash, for learned strategies (their own file: the test split)."""
    if not args.strategy.startswith("learned:"):
        return None
    from cramlite.learning.scoring import file_sha256

    return file_sha256(args.data)


def cmd_evaluate(args: argparse.Namespace) -> int:

    from cramlite.evaluation.evaluate import evaluate

    params = parse_params(args.params)
    strategy_checked(args.strategy, params=params, dims=args.dims, form=args.form)
    episodes, bad = _load_episodes(args)
    try:
        with progress_bar(len(episodes), "evaluate") as bar:
            result = evaluate(episodes, args.strategy, params, args.dims, args.form, args.metric,
                              args.repeats, args.seed, progress=bar.update,
                              protocol=args.protocol, data_sha256=_sha256(args))
    except StrategyError as exc:  # a plugin that raises or returns a non-candidate
        raise UserInputError(str(exc), field="--strategy") from None
    except ValueError as exc:  # e.g. expected-ape with a strategy that has memory
        raise UserInputError(str(exc), field="--metric") from None
    with quiet_broken_pipe():
        return _print_evaluation(args, result, bad)


def _print_evaluation(args: argparse.Namespace, result, bad) -> int:
    import json

    report = result.as_dict()
    report["skipped"] = [{"id": b.id, "reason": f"{b.field}: {b.message}"} for b in bad] + \
        report["skipped"]
    for item in result.skipped:
        print(f"cramlite evaluate: skipped episode {item[0]}: {item[1]}", file=sys.stderr)
    if args.json:
        print(json.dumps(report))
        return EXIT_OK
    if args.verbose:  # (one line per episode: 186 of them for the table-setting data)
        print(f"{'episode':<12} {'activity':<14} {'steps':>5} {args.metric:>12} "
              f"{'random':>8}")
        for row in report["per_episode"]:
            print(f"{row['id']:<12} {row['activity']:<14} {row['length']:>5} "
                  f"{row['score']:>12.3f} {row['random_baseline']:>8.3f}")
        print()
    print(f"{args.strategy} ({args.dims}, {args.form}, protocol {args.protocol}) on "
          f"{report['episodes']} episodes, metric {args.metric}: mean {report['mean']:.3f}, "
          f"median {report['median']:.3f} ({report['score_definition']})")
    for activity, summary in report["by_activity"].items():
        print(f"  {activity}: {summary['episodes']} episodes, mean {summary['mean']:.3f}, "
              f"median {summary['median']:.3f}")
    base = report["random_baseline"]
    print(f"  random baseline ({base['definition']}): mean {base['mean']:.3f}, "
          f"median {base['median']:.3f}")
    if not args.verbose:
        print("  (--verbose: a line per episode; --json: everything)")
    return EXIT_OK


def cmd_fit(args: argparse.Namespace) -> int:
    from cramlite.evaluation.evaluate import baseline_score
    from cramlite.evaluation.fit import fit, source_grid
    from cramlite.evaluation.report import write_fit

    dims = [d.strip() for d in args.dims.split(",") if d.strip()]
    if not dims:
        raise UserInputError(f"expected a comma-separated list of {', '.join(DIM_NAMES)}, "
                             f"got {args.dims!r}", field="--dims")
    for d in dims:
        if d not in DIM_NAMES:
            raise UserInputError(f"unknown projection {d!r}; expected a comma-separated list "
                                 f"of {', '.join(DIM_NAMES)}", field="--dims")
    strategy_checked(args.strategy, form=args.form)
    if args.temperature is not None and args.metric != "likelihood":
        raise UserInputError(f"applies to --metric likelihood only (the metric is "
                             f"{args.metric})", field="--temperature")
    temperature = DEFAULT_TEMPERATURE if args.temperature is None else args.temperature
    out = writable_folder(args.out)
    episodes, _ = _load_episodes(args)
    configs = source_grid(independent_mid=args.independent_mid)
    try:
        with progress_bar(len(episodes) * len(dims), f"fit {args.strategy}") as bar:
            result = fit(episodes, args.strategy, dims, args.metric, args.repeats, args.seed,
                         args.form, configs, progress=bar.update, protocol=args.protocol,
                         workers=args.workers, temperature=temperature)
    except StrategyError as exc:  # a plugin that raises or returns a non-candidate
        raise UserInputError(str(exc), field="--strategy") from None
    except ValueError as exc:
        raise UserInputError(str(exc), field="--metric") from None
    baselines = [baseline_score(ep, args.metric, protocol=args.protocol)[0] for ep in episodes]
    summary = write_fit(result, baselines, out)
    with quiet_broken_pipe():
        return _print_fit(args, episodes, summary)


def _print_fit(args: argparse.Namespace, episodes, summary) -> int:
    import json

    if args.json:
        print(json.dumps(summary))
        return EXIT_OK
    print(f"{args.strategy} fit on {len(episodes)} episodes, metric {args.metric}, "
          f"{summary['grid_points']} grid points per projection")
    for d, row in summary["by_projection"].items():
        params = ", ".join(f"{k}={v:.1f}" for k, v in row["params"].items())
        fitted = f"best {params}" if params else f"({args.strategy} takes no parameters)"
        print(f"  {d:<4} {fitted}: mean {row['mean']:.3f}, median {row['median']:.3f}")
        flat = {k: v for k, v in row["tied_best"].items() if v[1] > v[0]}
        if flat:  # (the first grid point of a plateau is only one of equals)
            print("       the grid points that fit exactly as well span "
                  + ", ".join(f"{k} {lo:.1f}-{hi:.1f}" for k, (lo, hi) in flat.items()))
    best = summary["best"]
    print(f"best: {best['dims']} mean {best['mean']:.3f}")
    if "source_params" in summary:
        src = summary["source_params"]
        print(f"source's parameters (0.2/0.3/1.2/1.7, {src['dims']}): mean {src['mean']:.3f}; "
              f"Wilcoxon vs best p = {src['test_vs_best']['p']:.3g}")
    tests = summary["tests_between_projections"]
    for pair, res in tests.get("wilcoxon", {}).items():
        if res["statistic"] is None:  # (no episode scored differently: nothing to test)
            print(f"  Wilcoxon {pair}: the same score on every episode, no test")
            continue
        print(f"  Wilcoxon {pair}: W = {res['statistic']}, p = {res['p']:.3g}")
    if "friedman" in tests:
        fr = tests["friedman"]
        print(f"  Friedman over {len(fr['groups'])} projections: chi2 = {fr['statistic']:.3f}, "
              f"p = {fr['p']:.3g}")
    for kind, path in summary["files"].items():
        print(f"wrote {kind}: {path}")
    return EXIT_OK


def cmd_simulate(args: argparse.Namespace) -> int:
    import json

    from cramlite.evaluation.data import load_episodes
    from cramlite.evaluation.simulate import simulate, write_episodes
    from cramlite.resources import resolve_data_path

    params = parse_params(args.params)
    strategy_checked(args.strategy, params=params, dims=args.dims, form=args.form)
    writable_file(args.out, "--out")
    like = str(resolve_data_path(args.like))
    episodes, _ = load_episodes(like)
    try:
        drawn = simulate(episodes, args.episodes or len(episodes), args.strategy, params,
                         args.temperature, args.seed, args.dims, args.form)
    except StrategyError as exc:
        raise UserInputError(str(exc), field="--strategy") from None
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_episodes(drawn, out)
    summary = {"episodes": len(drawn), "like": like, "strategy": args.strategy,
               "params": params, "dims": args.dims, "form": args.form,
               "temperature": args.temperature, "seed": args.seed,
               "choice_rule": "P(item) proportional to exp(-cost / temperature)",
               "file": str(out)}
    with quiet_broken_pipe():
        if args.json:
            print(json.dumps(summary))
        else:
            print(f"wrote {len(drawn)} episodes drawn from {args.strategy} "
                  f"({', '.join(f'{k}={v:g}' for k, v in params.items()) or 'its defaults'}; "
                  f"softmax over costs, temperature {args.temperature:g}; seed {args.seed}), "
                  f"the tasks of {args.like}: {out}")
    return EXIT_OK


#: A likelihood's softmax temperature (0 would make every other choice impossible; far
#: below 1e-6 a cost over it overflows).
temperature_float = float_in_range(1e-6, 1e6, "a temperature from 1e-6 to 1e6")
#: A simulation's softmax temperature (0: always the lowest cost).
simulate_temperature = float_in_range(0.0, 1e6, "a temperature from 0 to 1e6")


def _add_data_arguments(p: argparse.ArgumentParser, metrics: tuple[str, ...]) -> None:
    p.add_argument("data", help="CSV of recorded sequences (the published OPM format), or "
                                "a shipped set by name: table-setting (186 episodes), "
                                "cooking (123), clearing-up (17) or all (326)")
    p.add_argument("--strategy", default="opm", help="strategy name (see `cramlite strategies`)")
    p.add_argument("--metric", default="ape", choices=metrics,
                   help="ape: sampled APE (median over repeats); expected-ape: its exact "
                        "expectation; edit / edit-unrestricted: normalised Damerau-Levenshtein"
                        + ("; likelihood: the negative log-likelihood of the observed "
                           "choices under a softmax over the costs at --temperature (its "
                           "minimum: the maximum-likelihood fit; opm, nearest, opm-2step, "
                           "optimal)" if "likelihood" in metrics else ""))
    p.add_argument("--form", default="power", choices=("power", "additive", "product"),
                   help="functional form (Eq. 3.1-3.3)")
    add_protocol_argument(p)
    p.add_argument("--repeats", type=repeats_int, default=100,
                   help="repeats of the random tie-breaks (default 100)")
    p.add_argument("--seed", type=seed_int, default=0, help="random seed")
    p.add_argument("--on-bad-row", choices=("fail", "skip"), default="fail",
                   help="a row that cannot be used: stop (default) or skip and report it")
    p.add_argument("--json", action="store_true", help="print one JSON object")




def add_protocol_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("--protocol", default="heldout", choices=PROTOCOLS,
                   help="heldout (default): cramlite's conventions, a learned model scored on "
                        "its test episodes only; thesis: as behind the published figures; "
                        "reference: the published OPM code's conventions (see "
                        "docs/evaluation.md, Protocols)")


def register(sub: argparse._SubParsersAction) -> None:
    evaluate = sub.add_parser("evaluate", help="score a strategy against human sequences")
    _add_data_arguments(evaluate, METRICS)
    evaluate.add_argument("--params", help="e.g. strong_k=0.2,mid_k=0.3,food_k=1.2,c=1.7")
    evaluate.add_argument("--dims", default="xy", choices=DIM_NAMES, help="projection")
    evaluate.add_argument("--verbose", action="store_true",
                          help="also print a line per episode (before the summary)")
    evaluate.set_defaults(func=cmd_evaluate)

    fit_cmd = sub.add_parser("fit", help="grid-search a strategy's parameters (Table 3.4)")
    _add_data_arguments(fit_cmd, FIT_METRICS)
    fit_cmd.add_argument("--temperature", type=temperature_float,
                         help="with --metric likelihood: the choice rule's softmax "
                              "temperature, P(item) ~ exp(-cost / T) (default "
                              f"{DEFAULT_TEMPERATURE}, as `simulate` draws)")
    fit_cmd.add_argument("--dims", default="xy,xyz",
                         help="comma-separated projections to fit (default xy,xyz)")
    fit_cmd.add_argument("--independent-mid", action="store_true",
                         help="grid mid k independently (0.1-1.0) instead of strong k + 0.1")
    fit_cmd.add_argument("--out", default="fit-results",
                         help="folder for surface.csv, fit.json, error_by_projection.png "
                              "(default fit-results)")
    fit_cmd.add_argument("--workers", type=workers_int, default=os.cpu_count() or 1,
                         help="processes for strategies scored point by point (default: "
                              "all cores); opm, nearest, opm-2step and optimal under APE are "
                              "vectorised over the grid")
    fit_cmd.set_defaults(func=cmd_fit)

    sim = sub.add_parser("simulate", help="synthetic episodes drawn from a strategy "
                                          "(parameter recovery)")
    sim.add_argument("--like", default="table-setting",
                     help="the recorded episodes whose tasks are copied (items, positions, "
                          "start positions): a CSV or a shipped set (default table-setting)")
    sim.add_argument("--strategy", default="opm",
                     help="an OPM-family strategy (its cost per item drives the choice)")
    sim.add_argument("--params", help="e.g. strong_k=0.4,mid_k=0.5,food_k=1.5,c=1.3")
    sim.add_argument("--dims", default="xy", choices=DIM_NAMES, help="projection")
    sim.add_argument("--form", default="power", choices=("power", "additive", "product"),
                     help="functional form (Eq. 3.1-3.3)")
    sim.add_argument("--temperature", type=simulate_temperature, default=DEFAULT_TEMPERATURE,
                     help="softmax over costs: P(item) ~ exp(-cost / T); 0 takes the "
                          f"lowest cost (default {DEFAULT_TEMPERATURE})")
    sim.add_argument("--episodes", type=episodes_int,
                     help="how many (default: as many as --like has; the j-th copies the "
                          "task of episode j modulo that)")
    sim.add_argument("--seed", type=seed_int, default=0, help="random seed")
    sim.add_argument("--out", default="simulated.csv",
                     help="the CSV to write (default simulated.csv)")
    sim.add_argument("--json", action="store_true", help="print one JSON object")
    sim.set_defaults(func=cmd_simulate)
