"""`cramlite bench`: many trials, locally or on a cluster, and their summary."""

from __future__ import annotations

import argparse
import sys

from cramlite.bench.execute import EXECUTORS
from cramlite.cli.common import (
    EXIT_OK,
    EXIT_PLAN_FAILED,
    comma_list,
    non_negative_int,
    positive_int,
)
from cramlite.errors import UserInputError
from cramlite.plan_names import PLAN_NAMES


def cmd_bench(args: argparse.Namespace) -> int:
    import os
    from dataclasses import replace
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
    strategies = comma_list(args.strategies)
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
    for name in comma_list(args.setups):
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
    if args.traces:
        traces = out / "traces"
        specs = [replace(s, trace=str(traces / f"{s.setup}-{s.strategy}-{s.trial}.jsonl"))
                 for s in specs]
    done = store.done_keys()
    todo = [spec for spec in specs if spec.key not in done]
    workers = args.workers or os.cpu_count() or 1
    store.write_metadata({k: v for k, v in vars(args).items() if k != "func"}, args.executor)
    where = (f"Dask scheduler {args.scheduler}, {2 * workers} trials in flight" if args.scheduler
             else f"{workers} worker(s), executor {args.executor}")
    print(f"bench: {len(specs)} trials ({len(specs) - len(todo)} already in {store.path}), "
          f"{where}", file=sys.stderr)
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



def register(sub: argparse._SubParsersAction) -> None:
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
    bench.add_argument("--trials", type=positive_int, default=10,
                       help="trials per setup and strategy (default 10)")
    bench.add_argument("--seed", type=non_negative_int, default=0,
                       help="batch seed; each trial's seed derives from it, the setup and "
                            "the trial index")
    bench.add_argument("--workers", type=positive_int, default=None,
                       help="worker processes (default: number of CPUs); with --scheduler, "
                            "half the number of trials kept in flight on the cluster")
    bench.add_argument("--executor", choices=EXECUTORS, default="local",
                       help="local process pool (default) or a Dask cluster")
    bench.add_argument("--scheduler", help="Dask scheduler address (default: a local cluster)")
    bench.add_argument("--all-orders", action="store_true",
                       help="add every permutation of each setup's items as fixed-order trials")
    bench.add_argument("--random-setups", type=positive_int, default=None, metavar="N",
                       help="add N random setups (saved under OUT/setups)")
    bench.add_argument("--plan", default="set-table", choices=PLAN_NAMES, help="which plan")
    bench.add_argument("--out", default="results", help="results folder (default results)")
    bench.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    bench.add_argument("--traces", action="store_true",
                       help="write each trial's trace to OUT/traces/SETUP-STRATEGY-TRIAL.jsonl "
                            "(replay them with `cramlite replay`)")
    bench.set_defaults(func=cmd_bench)
