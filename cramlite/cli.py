"""The `cramlite` command line. User mistakes end with one line on stderr and exit 2."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence

from cramlite.errors import UserInputError

EXIT_OK, EXIT_PLAN_FAILED, EXIT_BAD_INPUT = 0, 1, 2


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2, as for every user mistake
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


def cmd_show(args: argparse.Namespace) -> int:
    from cramlite.world import World, load_setup
    from cramlite.world.render import render, save_png

    setup = load_setup(args.setup)
    out = args.out or f"{setup.name}.png"
    with World.from_setup(setup) as world:
        path = save_png(render(world, args.width, args.height), out)
    print(f"wrote {path} ({setup.name}: {len(setup.items)} items)")
    return EXIT_OK


def cmd_strategies(args: argparse.Namespace) -> int:
    from cramlite.strategies import available_strategies

    listing = available_strategies()
    width = max(map(len, listing))
    for name, summary in listing.items():
        print(f"{name:<{width}}  {summary}")
    return EXIT_OK


def cmd_order(args: argparse.Namespace) -> int:
    import json

    from cramlite.strategies.service import answer_text

    if args.request == "-":
        text, source = sys.stdin.read(), "<stdin>"
    else:
        try:
            with open(args.request, encoding="utf-8") as handle:
                text, source = handle.read(), args.request
        except OSError as exc:
            raise UserInputError(f"cannot read request ({exc.strerror})",
                                 source=args.request) from None
    print(json.dumps(answer_text(text, source)))
    return EXIT_OK


def _parse_params(text: str | None) -> dict[str, float]:
    from cramlite.strategies import OPMParams

    params: dict[str, float] = {}
    for part in filter(None, (text or "").split(",")):
        name, sep, value = part.partition("=")
        name = name.strip()
        if not sep or name not in OPMParams.names():
            raise UserInputError(f"expected NAME=VALUE with NAME one of "
                                 f"{', '.join(OPMParams.names())}, got {part!r}",
                                 field="--params")
        try:
            params[name] = float(value)
        except ValueError:
            raise UserInputError(f"expected a number for {name}, got {value!r}",
                                 field="--params") from None
    return params


def _load_episodes(args: argparse.Namespace):
    from cramlite.evaluation.data import load_episodes

    episodes, bad = load_episodes(args.data, on_bad_row=args.on_bad_row)
    for row in bad:
        print(f"cramlite {args.command}: skipped {args.data}: {row}", file=sys.stderr)
    if not episodes:
        raise UserInputError("no usable episodes", source=args.data)
    return episodes, bad


def _progress(total: float, desc: str):
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="ep", disable=not sys.stderr.isatty(),
                leave=False, dynamic_ncols=True)


def _strategy_checked(name: str, **kwargs) -> None:
    from cramlite.strategies import StrategyError, make_strategy

    try:
        make_strategy(name, **kwargs)
    except StrategyError as exc:
        raise UserInputError(str(exc), field="--strategy") from None


def cmd_evaluate(args: argparse.Namespace) -> int:
    import json

    from cramlite.evaluation.evaluate import evaluate

    params = _parse_params(args.params)
    _strategy_checked(args.strategy, params=params, dims=args.dims, form=args.form)
    episodes, bad = _load_episodes(args)
    try:
        with _progress(len(episodes), "evaluate") as bar:
            result = evaluate(episodes, args.strategy, params, args.dims, args.form, args.metric,
                              args.repeats, args.seed, progress=bar.update)
    except ValueError as exc:  # e.g. expected-ape with a strategy that has memory
        raise UserInputError(str(exc), field="--metric") from None
    report = result.as_dict()
    report["skipped"] = [{"id": b.id, "reason": f"{b.field}: {b.message}"} for b in bad] + \
        report["skipped"]
    for item in result.skipped:
        print(f"cramlite evaluate: skipped episode {item[0]}: {item[1]}", file=sys.stderr)
    if args.json:
        print(json.dumps(report))
        return EXIT_OK
    print(f"{'episode':<12} {'activity':<14} {'steps':>5} {args.metric:>12} {'random':>8}")
    for row in report["per_episode"]:
        print(f"{row['id']:<12} {row['activity']:<14} {row['length']:>5} {row['score']:>12.3f} "
              f"{row['random_baseline']:>8.3f}")
    print(f"\n{args.strategy} ({args.dims}, {args.form}) on {report['episodes']} episodes, "
          f"metric {args.metric}: mean {report['mean']:.3f}, median {report['median']:.3f}")
    for activity, summary in report["by_activity"].items():
        print(f"  {activity}: {summary['episodes']} episodes, mean {summary['mean']:.3f}, "
              f"median {summary['median']:.3f}")
    base = report["random_baseline"]
    print(f"  random order ({'exact' if base['exact'] else 'sampled'}): mean {base['mean']:.3f},"
          f" median {base['median']:.3f}")
    return EXIT_OK


def cmd_fit(args: argparse.Namespace) -> int:
    import json
    from pathlib import Path

    from cramlite.evaluation.evaluate import baseline_score, episode_rng
    from cramlite.evaluation.fit import fit, source_grid
    from cramlite.evaluation.report import write_fit
    from cramlite.strategies import DIMS

    dims = [d.strip() for d in args.dims.split(",") if d.strip()]
    for d in dims:
        if d not in DIMS:
            raise UserInputError(f"unknown projection {d!r}; expected a comma-separated list "
                                 f"of {', '.join(DIMS)}", field="--dims")
    _strategy_checked(args.strategy, form=args.form)
    episodes, _ = _load_episodes(args)
    configs = source_grid(independent_mid=args.independent_mid)
    try:
        with _progress(len(episodes) * len(dims), f"fit {args.strategy}") as bar:
            result = fit(episodes, args.strategy, dims, args.metric, args.repeats, args.seed,
                         args.form, configs, progress=bar.update)
    except ValueError as exc:
        raise UserInputError(str(exc), field="--metric") from None
    baselines = [baseline_score(ep, args.metric, episode_rng(args.seed, i))[0]
                 for i, ep in enumerate(episodes)]
    summary = write_fit(result, baselines, Path(args.out))
    if args.json:
        print(json.dumps(summary))
        return EXIT_OK
    print(f"{args.strategy} fit on {len(episodes)} episodes, metric {args.metric}, "
          f"{summary['grid_points']} grid points per projection")
    for d, row in summary["by_projection"].items():
        params = ", ".join(f"{k}={v:.1f}" for k, v in row["params"].items())
        print(f"  {d:<4} best {params}: mean {row['mean']:.3f}, median {row['median']:.3f}")
    best = summary["best"]
    print(f"best: {best['dims']} mean {best['mean']:.3f}")
    if "source_params" in summary:
        src = summary["source_params"]
        print(f"source's parameters (0.2/0.3/1.2/1.7, {src['dims']}): mean {src['mean']:.3f}; "
              f"Wilcoxon vs best p = {src['test_vs_best']['p']:.3g}")
    tests = summary["tests_between_projections"]
    for pair, res in tests.get("wilcoxon", {}).items():
        print(f"  Wilcoxon {pair}: W = {res['statistic']}, p = {res['p']:.3g}")
    if "friedman" in tests:
        fr = tests["friedman"]
        print(f"  Friedman over {len(fr['groups'])} projections: chi2 = {fr['statistic']:.3f}, "
              f"p = {fr['p']:.3g}")
    for kind, path in summary["files"].items():
        print(f"wrote {kind}: {path}")
    return EXIT_OK


def cmd_run(args: argparse.Namespace) -> int:
    import json

    from cramlite.trial import TrialRunner
    from cramlite.world import load_setup

    params = _parse_params(args.params)
    _strategy_checked(args.strategy, params=params, dims=args.dims)
    setup = load_setup(args.setup)
    try:
        runner = TrialRunner(setup, gui=args.gui)
    except RuntimeError as exc:  # no display for --gui
        raise UserInputError(str(exc), field="--gui") from None
    with runner:
        result = runner.run(args.strategy, args.plan, args.seed, params=params, dims=args.dims)
        if args.image:
            from cramlite.world.render import render, save_png

            save_png(render(runner.world), args.image)
    if args.json:
        data = result.as_dict()
        if not args.log:
            data.pop("log")
        print(json.dumps(data))
    else:
        status = "success" if result.success else "FAILED"
        print(f"{result.setup} {result.plan} with {result.strategy} (seed {result.seed}): {status}")
        print(f"  order: {', '.join(result.order)}")
        print(f"  driven base path {result.base_path_m:.2f} m, straight-line legs "
              f"{result.straight_line_m:.2f} m")
        print(f"  wall {result.wall_s:.2f} s, robot time {result.robot_time_s:.2f} s")
        for failure in result.failures:
            print(f"  failure: {failure['type']}: {failure['message']}")
        if args.log:
            for line in result.log:
                print(f"  log: {line}")
    return EXIT_OK if result.success else EXIT_PLAN_FAILED


def _comma_list(text: str) -> list[str]:
    return [part.strip() for part in text.split(",") if part.strip()]


def cmd_bench(args: argparse.Namespace) -> int:
    import os
    from pathlib import Path

    from cramlite.bench.execute import run_batch
    from cramlite.bench.plots import write_plots
    from cramlite.bench.progress import Progress
    from cramlite.bench.random_setups import generate_setups
    from cramlite.bench.specs import make_specs
    from cramlite.bench.store import TrialStore, row_key
    from cramlite.bench.summary import order_percentiles, paired_tests, summarise, write_summary
    from cramlite.strategies import StrategyError, available_strategies, strategy_class
    from cramlite.world.setup import builtin_setup_names, load_setup

    if args.scheduler and args.executor != "dask":
        raise UserInputError("a scheduler address needs --executor dask", field="--scheduler")
    strategies = _comma_list(args.strategies)
    if not strategies:
        raise UserInputError("expected at least one strategy", field="--strategies")
    for name in strategies:
        try:
            strategy_class(name)
        except StrategyError:
            raise UserInputError(f"unknown strategy {name!r}; valid: "
                                 f"{', '.join(available_strategies())} or module:Class",
                                 field="--strategies") from None
    setups = {}
    for name in _comma_list(args.setups):
        try:
            setup = load_setup(name)
        except UserInputError as exc:
            if exc.field is None:  # no such setup at all
                raise UserInputError(f"unknown setup {name!r}; valid: "
                                     f"{', '.join(builtin_setup_names())} or a path to a "
                                     "setup file", field="--setups") from None
            raise
        if setup.name in setups:
            raise UserInputError(f"two setups are named {setup.name!r}", field="--setups")
        setups[setup.name] = setup
    out = Path(args.out)
    store = TrialStore(out)
    store.repair()
    if args.random_setups:
        for name, path in generate_setups(args.random_setups, args.seed,
                                          out / "setups").items():
            setups[name] = load_setup(path)
    if not setups:
        raise UserInputError("expected at least one setup", field="--setups")
    all_orders = ({n: list(s.baseline_order) for n, s in setups.items()}
                  if args.all_orders else None)
    specs = make_specs({n: s.source for n, s in setups.items()}, strategies, args.trials,
                       args.seed, args.plan, all_orders)
    done = store.done_keys()
    todo = [spec for spec in specs if spec.key not in done]
    workers = args.workers or os.cpu_count() or 1
    store.write_metadata({k: v for k, v in vars(args).items() if k != "func"}, args.executor)
    print(f"bench: {len(specs)} trials ({len(specs) - len(todo)} already in {store.path}), "
          f"{workers} worker(s), executor {args.executor}", file=sys.stderr)
    progress = Progress(len(todo), already=len(specs) - len(todo))

    def record(row: dict) -> None:
        store.append(row)
        progress.update(row)

    try:
        outcome = run_batch(todo, record, args.executor, workers, args.scheduler)
    finally:
        progress.close()
    wanted = {spec.key for spec in specs}
    rows = [r for r in store.rows() if row_key(r) in wanted]
    summary = summarise(rows, {n: s.baseline_order for n, s in setups.items()})
    tests = [paired_tests(rows, s) for s in strategies if s != "baseline"] \
        if "baseline" in strategies else []
    text = write_summary(out, summary, tests, order_percentiles(rows) if args.all_orders else [])
    plots = [] if args.no_plots else write_plots(rows, out)
    print(text)
    print(f"wrote {store.path}, {out / 'summary.csv'}, {out / 'summary.md'}"
          + (f", {len(plots)} plots" if plots else
             ("" if args.no_plots else " (no plots: pip install cramlite[plots])")))
    if outcome.interrupted:
        print(f"bench: interrupted; {len(rows)} of {len(specs)} trials are in {store.path}. "
              "Run the same command again to finish the rest.", file=sys.stderr)
        return 130
    failed = [r for r in rows if str(r["success"]) != "True"]
    if failed:
        print(f"bench: {len(failed)} of {len(rows)} trials failed (see error/failures columns)",
              file=sys.stderr)
    return EXIT_OK if not failed else EXIT_PLAN_FAILED


def _int_at_least(minimum: int, wording: str) -> Callable[[str], int]:
    """An argparse type: a whole number >= minimum (the message names what was expected)."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = None
        if value is None or value < minimum:
            raise argparse.ArgumentTypeError(f"expected {wording}, got {text!r}")
        return value
    return parse


_positive_int = _int_at_least(1, "a positive integer")
_non_negative_int = _int_at_least(0, "a whole number >= 0")


def _add_data_arguments(p: argparse.ArgumentParser, metrics: tuple[str, ...]) -> None:
    from cramlite.strategies import FORMS

    p.add_argument("data", help="CSV of recorded sequences (the published OPM format)")
    p.add_argument("--strategy", default="opm", help="strategy name (see `cramlite strategies`)")
    p.add_argument("--metric", default="ape", choices=metrics,
                   help="ape: sampled APE (median over repeats); expected-ape: its exact "
                        "expectation; edit / edit-unrestricted: normalised Damerau-Levenshtein")
    p.add_argument("--form", default="power", choices=FORMS, help="functional form (Eq. 3.1-3.3)")
    p.add_argument("--repeats", type=_positive_int, default=100,
                   help="repeats of the random tie-breaks (default 100)")
    p.add_argument("--seed", type=_non_negative_int, default=0, help="random seed")
    p.add_argument("--on-bad-row", choices=("fail", "skip"), default="fail",
                   help="a row that cannot be used: stop (default) or skip and report it")
    p.add_argument("--json", action="store_true", help="print one JSON object")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="cramlite", description="A lightweight, ROS-free robot plan executive.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    show = sub.add_parser("show", help="draw a setup headless into a PNG")
    show.add_argument("setup", help="v1..v5 or a path to a setup YAML file")
    show.add_argument("--out", help="PNG file to write (default: SETUPNAME.png)")
    show.add_argument("--width", type=int, default=1024, help="image width in pixels")
    show.add_argument("--height", type=int, default=768, help="image height in pixels")
    show.set_defaults(func=cmd_show)

    strategies = sub.add_parser("strategies", help="list the ordering strategies by name")
    strategies.set_defaults(func=cmd_strategies)

    order = sub.add_parser(
        "order", help="answer one JSON ordering request (the OPM service without ROS)",
        description="Reads {\"robot\": [x,y,z], \"items\": [{\"name\", \"position\", "
                    "\"k\"|\"category\", \"c\"|\"contained\"}], \"strategy\", \"params\", "
                    "\"dims\", \"form\", \"seed\", \"then_at\"} and prints "
                    "{\"next\", \"costs\", \"order\"}.")
    order.add_argument("request", nargs="?", default="-", help="JSON file, or - for stdin")
    order.set_defaults(func=cmd_order)

    from cramlite.evaluation.evaluate import METRICS
    from cramlite.strategies import DIMS

    evaluate = sub.add_parser("evaluate", help="score a strategy against human sequences")
    _add_data_arguments(evaluate, METRICS)
    evaluate.add_argument("--params", help="e.g. strong_k=0.2,mid_k=0.3,food_k=1.2,c=1.7")
    evaluate.add_argument("--dims", default="xy", choices=list(DIMS), help="projection")
    evaluate.set_defaults(func=cmd_evaluate)

    fit_cmd = sub.add_parser("fit", help="grid-search a strategy's parameters (Table 3.4)")
    _add_data_arguments(fit_cmd, METRICS)
    fit_cmd.add_argument("--dims", default="xy,xyz",
                         help="comma-separated projections to fit (default xy,xyz)")
    fit_cmd.add_argument("--independent-mid", action="store_true",
                         help="grid mid k independently (0.1-1.0) instead of strong k + 0.1")
    fit_cmd.add_argument("--out", default="fit-results",
                         help="folder for surface.csv, fit.json, error_by_projection.png")
    fit_cmd.set_defaults(func=cmd_fit)

    from cramlite.trial import PLAN_NAMES

    run = sub.add_parser("run", help="run one trial of a plan in a setup (headless)",
                         description="Exit code 0: success, 1: the plan failed, 2: bad input.")
    run.add_argument("setup", help="v1..v5, another shipped setup, or a path to a setup file")
    run.add_argument("--plan", default="set-table", choices=PLAN_NAMES, help="which plan")
    run.add_argument("--strategy", default="baseline",
                     help="ordering strategy (see `cramlite strategies`; default baseline)")
    run.add_argument("--params", help="strategy parameters, e.g. mid_k=0.3,c=1.7")
    run.add_argument("--dims", default="xy", choices=list(DIMS), help="strategy projection")
    run.add_argument("--seed", type=_non_negative_int, default=0, help="random seed")
    run.add_argument("--gui", action="store_true", help="show the PyBullet GUI (needs a display)")
    run.add_argument("--json", action="store_true", help="print one JSON object")
    run.add_argument("--log", action="store_true", help="also print what the plan did")
    run.add_argument("--image", help="write a PNG of the scene after the trial")
    run.set_defaults(func=cmd_run)

    from cramlite.bench.execute import EXECUTORS

    bench = sub.add_parser(
        "bench", help="run many trials (setups x strategies x trials) and summarise them",
        description="Defaults reproduce the source's experiment: v1-v5 x {opm, baseline} x "
                    "10 trials. Results go to OUT/trials.csv (appended as trials finish; "
                    "rerunning with the same --out resumes), OUT/summary.csv|md and plots. "
                    "Exit code 0: every trial succeeded, 1: some failed, 2: bad arguments, "
                    "130: interrupted.")
    bench.add_argument("--setups", default="v1,v2,v3,v4,v5",
                       help="comma-separated setup names or paths (default v1..v5)")
    bench.add_argument("--strategies", default="opm,baseline",
                       help="comma-separated strategy names (default opm,baseline)")
    bench.add_argument("--trials", type=_positive_int, default=10,
                       help="trials per setup and strategy (default 10)")
    bench.add_argument("--seed", type=_non_negative_int, default=0,
                       help="batch seed; each trial's seed derives from it, the setup and "
                            "the trial index")
    bench.add_argument("--workers", type=_positive_int, default=None,
                       help="worker processes (default: number of CPUs)")
    bench.add_argument("--executor", choices=EXECUTORS, default="local",
                       help="local process pool (default) or a Dask cluster")
    bench.add_argument("--scheduler", help="Dask scheduler address (default: a local cluster)")
    bench.add_argument("--all-orders", action="store_true",
                       help="add every permutation of each setup's items as fixed-order trials")
    bench.add_argument("--random-setups", type=_positive_int, default=None, metavar="N",
                       help="add N random setups (saved under OUT/setups)")
    bench.add_argument("--plan", default="set-table", choices=PLAN_NAMES, help="which plan")
    bench.add_argument("--out", default="results", help="results folder (default results)")
    bench.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    bench.set_defaults(func=cmd_bench)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    func: Callable[[argparse.Namespace], int] = args.func
    try:
        return func(args)
    except UserInputError as exc:
        print(f"cramlite {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("cramlite: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
