"""`cramlite bench`: many trials, locally or on a cluster, and their summary."""

from __future__ import annotations

import argparse
import os

from cramlite.cli.common import (
    BACKEND_HELP,
    CARRY_HELP,
    EXIT_OK,
    EXIT_PLAN_FAILED,
    INJECT_HELP,
    comma_list,
    command_help,
    int_in_range,
    positive_float,
    seed_int,
    whole_number,
    workers_int,
)
from cramlite.errors import UserInputError
from cramlite.plan_names import PLAN_HELP

EXECUTORS = ("local", "dask")  # cramlite.bench.execute.EXECUTORS (tested)
DEFAULT_TRIAL_TIMEOUT_S = 300.0  # cramlite.bench.execute.DEFAULT_TRIAL_TIMEOUT_S (tested)
MAX_TRIALS = 1_000_000
#: --all-orders runs n! trials per setup: 10 items are 3,628,800 already.
MAX_ALL_ORDERS_ITEMS = 10
#: Local worker processes per CPU at most (each holds a simulator, ~300 MB).
MAX_WORKERS_PER_CPU = 4
EXIT_TERMINATED = 143


def _strategies(text: str) -> list[str]:
    from cramlite.strategies import StrategyError, available_strategies, strategy_class

    strategies = comma_list(text)
    if not strategies:
        raise UserInputError("expected at least one strategy", field="--strategies")
    for i, name in enumerate(strategies):
        if name in strategies[:i]:
            raise UserInputError(f"{name!r} is listed twice; expected each strategy once",
                                 field="--strategies")
        try:
            strategy_class(name)
        except StrategyError as exc:
            detail = "" if str(exc).startswith("unknown") else f" ({exc})"
            raise UserInputError(f"unknown strategy {name!r}{detail}; valid: "
                                 f"{', '.join(available_strategies())} or module:Class",
                                 field="--strategies") from None
    return strategies


def _backends(args: argparse.Namespace) -> list[str]:
    """--backend NAME or --backends A,B (each checked: installed here), or the default."""
    from cramlite.cli.common import chosen_backend

    if args.backend and args.backends_list:
        raise UserInputError("give --backend or --backends, not both", field="--backends")
    if args.backends_list is not None:
        names = [part.strip() for part in args.backends_list.split(",")]
        if not any(names) or not all(names):
            raise UserInputError(f"expected backend names separated by commas, got "
                                 f"{args.backends_list!r}", field="--backends")
    else:
        names = [args.backend]
    out = []
    for name in names:
        try:
            backend = chosen_backend(name)
        except UserInputError as exc:
            if args.backends_list is None:
                raise
            raise UserInputError(exc.detail, field="--backends") from None
        if backend in out:
            raise UserInputError(f"{backend!r} is listed twice; expected each backend once",
                                 field="--backends")
        out.append(backend)
    return out


def _setups(text: str) -> dict:
    """Load and check every setup now (geometry included), so a bad one is refused before
    any trial runs."""
    from cramlite.scene.scene import PlanningScene
    from cramlite.scene.validate import check_setup
    from cramlite.world.setup import builtin_setup_names, load_setup

    setups = {}
    for name in comma_list(text):
        try:
            setup = load_setup(name)
        except UserInputError as exc:
            if exc.field is None and not os.path.exists(name):  # no such setup at all
                raise UserInputError(f"unknown setup {name!r}; valid: "
                                     f"{', '.join(builtin_setup_names())} or a path to a "
                                     "setup file", field="--setups") from None
            raise
        if setup.name in setups:
            raise UserInputError(f"two setups are named {setup.name!r}", field="--setups")
        check_setup(PlanningScene(setup))
        setups[setup.name] = setup
    return setups


def _workers(args: argparse.Namespace) -> int | None:
    cpus = os.cpu_count() or 1
    if args.executor == "local" and args.workers and args.workers > MAX_WORKERS_PER_CPU * cpus:
        raise UserInputError(f"{args.workers} local workers on {cpus} CPU(s); expected at most "
                             f"{MAX_WORKERS_PER_CPU * cpus}", field="--workers")
    if args.executor == "dask" and args.scheduler:
        return args.workers  # None: as many as the cluster has worker processes
    return args.workers or cpus


def _results_folder(path: str):
    """The --out folder, created, locked for this bench (exit 2 naming the holder)."""
    from pathlib import Path

    from cramlite.bench.lock import FolderBusy, FolderLock
    from cramlite.resources import data_dir, worlds_dir

    out = Path(path)
    if out.exists() and not out.is_dir():
        raise UserInputError("is a file; expected a folder for the results", source=path,
                             field="--out")
    shipped = [d.resolve() for d in (worlds_dir(), data_dir())]
    if any(out.resolve().is_relative_to(d) for d in shipped):  # (its setups would be
        # listed as shipped ones)
        raise UserInputError("is inside cramlite's own worlds or data folder; expected a "
                             "folder of yours for the results", source=path, field="--out")
    try:
        out.mkdir(parents=True, exist_ok=True)
        lock = FolderLock(out)
        lock.acquire()
    except FolderBusy as exc:
        raise UserInputError(f"in use by another bench ({exc.holder or 'holder unknown'}); "
                             "expected a folder no other bench is writing into", source=path,
                             field="--out") from None
    except OSError as exc:
        raise UserInputError(f"cannot create or write the folder ({exc.strerror or exc})",
                             source=path, field="--out") from None
    return out, lock


def cmd_bench(args: argparse.Namespace) -> int:
    if args.scheduler and args.executor != "dask":
        raise UserInputError("a scheduler address needs --executor dask", field="--scheduler")
    from cramlite.bench.execute import SchedulerUnreachable, check_scheduler

    if args.executor == "dask":
        try:
            if args.scheduler:
                check_scheduler(args.scheduler)
            else:
                import distributed  # noqa: F401
        except SchedulerUnreachable as exc:
            raise UserInputError(str(exc), field="--scheduler") from None
        except ImportError:
            raise UserInputError("the dask executor needs Dask: pip install 'cramlite[dask]'",
                                 field="--executor") from None
    from cramlite.bench.summary import default_reference
    from cramlite.designators.injection import inject_text, parse_inject
    from cramlite.plan_registry import plan_function

    args.inject_text = inject_text(parse_inject(args.inject))  # (checked; the key's spelling)
    strategies = _strategies(args.strategies)
    if args.reference and args.reference not in strategies:
        raise UserInputError(f"{args.reference!r} is not one of the strategies run "
                             f"({', '.join(strategies)})", field="--reference")
    # (resolved here, from the order asked, not from the order trials finish in; the
    # metadata records it so that `cramlite report` compares with the same one)
    args.reference = args.reference or default_reference(strategies)
    plan_function(args.plan)  # (a plan that cannot load: one line, exit 2, before any trial)
    args.backends = _backends(args)
    args.carry = _carries(args.carry)
    workers = _workers(args)
    args.workers = workers  # (the metadata and the report show the number used)
    setups = _setups(args.setups)
    if not setups and not args.random_setups:
        raise UserInputError("expected at least one setup", field="--setups")
    if args.all_orders:
        for name, setup in setups.items():
            if len(setup.items) > MAX_ALL_ORDERS_ITEMS:
                raise UserInputError(f"setup {name!r} has {len(setup.items)} items; "
                                     f"--all-orders runs n! trials and expects at most "
                                     f"{MAX_ALL_ORDERS_ITEMS} items", field="--all-orders")
    out, lock = _results_folder(args.out)
    try:
        return _run(args, strategies, setups, workers, out)
    finally:
        lock.release()


def _carries(text: str) -> list[int]:
    """--carry 1, 2 or 1,2: distinct, each 1 or 2, in the order given."""
    parts = [part.strip() for part in str(text).split(",")]
    if not parts or any(p not in ("1", "2") for p in parts) or len(set(parts)) < len(parts):
        raise UserInputError(f"expected 1, 2 or 1,2 (items carried at once: one per hand), "
                             f"got {text!r}", field="--carry")
    return [int(p) for p in parts]


def _run(args, strategies, setups, workers, out) -> int:
    import signal

    from cramlite.bench.execute import SchedulerUnreachable, StopNow, run_batch
    from cramlite.bench.progress import Progress
    from cramlite.bench.random_setups import generate_setups
    from cramlite.bench.specs import BatchPlan, SetupEntry
    from cramlite.bench.store import StoreMismatch, TrialStore, row_key
    from cramlite.bench.summary import (
        order_percentiles,
        reference_tests,
        summarise,
        write_summary,
    )
    from cramlite.world.setup import load_setup

    store = TrialStore(out)
    store.repair()
    if args.random_setups:
        for name, path in generate_setups(args.random_setups, args.seed,
                                          out / "setups").items():
            setups[name] = load_setup(path)
    if not setups:
        raise UserInputError("expected at least one setup", field="--setups")
    try:
        store.check_compatible({n: s.content_hash for n, s in setups.items()})
    except StoreMismatch as exc:
        raise UserInputError(str(exc), field="--out") from None
    from cramlite.bench.specs import FIXED_ORDER
    from cramlite.plugins import trial_code_hash

    code = {s: trial_code_hash(args.plan, s) for s in [*strategies, FIXED_ORDER]}
    plan = BatchPlan({n: SetupEntry(str(s.source), s.content_hash, tuple(s.baseline_order))
                      for n, s in setups.items()}, strategies, args.trials, args.seed,
                     args.plan, args.all_orders,
                     str(out / "traces") if args.traces else "", tuple(args.backends), code,
                     os.getcwd(), args.inject_text, tuple(args.carry))
    done = {key for key in store.done_keys() if plan.contains(key)}
    total = plan.total()
    from cramlite.bench.store import key_digest

    store.write_metadata({k: v for k, v in vars(args).items() if k != "func"}, args.executor,
                         batch=[key_digest(spec.key) for spec in plan])
    where = (f"Dask scheduler {args.scheduler}" if args.scheduler
             else f"{workers} worker(s), executor {args.executor}")
    where += f", backend {', '.join(args.backends)}"
    if args.carry != [1]:
        where += f", carrying {' and '.join(map(str, args.carry))} at once"
    progress = Progress(total - len(done), already=len(done))
    progress.say(f"{total} trials ({len(done)} already in {store.path}), {where}, trial "
                 f"timeout {args.trial_timeout:g} s")

    def record(row: dict) -> None:
        store.append(row)
        progress.update(row)

    def terminate(signum, frame):
        raise StopNow()

    previous = signal.signal(signal.SIGTERM, terminate)
    try:
        outcome = run_batch((spec for spec in plan if spec.key not in done), record,
                            args.executor, workers, args.scheduler, args.trial_timeout,
                            notify=progress.say)
    except SchedulerUnreachable as exc:
        raise UserInputError(str(exc), field="--scheduler") from None
    finally:
        signal.signal(signal.SIGTERM, previous)
        progress.close()
    rows = [r for r in store.rows() if plan.contains(row_key(r))]
    if outcome.interrupted:
        progress.say(f"{'terminated' if outcome.stopped_now else 'interrupted'}; {len(rows)} "
                     f"of {total} trials are in {store.path}. Run the same command again to "
                     f"finish the rest (`cramlite report {out}` shows what is there).")
        return EXIT_TERMINATED if outcome.stopped_now else 130
    from cramlite.bench.labels import by_backend

    rows = by_backend(rows)  # (several backends: each strategy labelled with its own)
    summary = summarise(rows, {n: s.baseline_order for n, s in setups.items()})
    tests = reference_tests(rows, args.reference)
    from cramlite.bench.agreement import backend_agreement, injection_counts
    from cramlite.bench.carrying import carry_savings

    text = write_summary(out, summary, tests, order_percentiles(rows) if args.all_orders else [],
                         backend_agreement(rows), injection_counts(rows), carry_savings(rows))
    failed = [r for r in rows if str(r["success"]) != "True"]
    if failed:
        progress.say(f"{len(failed)} of {len(rows)} trials failed (see the error and "
                     "failures columns)")
    print(text)
    from cramlite.report import build_report
    from cramlite.report.build import DEFAULT_MAX_REPLAYS, have_matplotlib

    plots = not args.no_plots and have_matplotlib()
    print(f"wrote {store.path}, {out / 'summary.csv'}, {out / 'summary.md'}"
          + ("; the plots and the report next" if plots else
             ("" if args.no_plots else " (no plots: pip install cramlite[plots])")),
          flush=True)
    # (the report draws the plots, on several processes with its other pictures, and
    # puts copies in the bench's folder)
    page = build_report(out, figures=not args.no_plots, running=False,
                        max_replays=0 if args.no_plots else DEFAULT_MAX_REPLAYS,
                        say=progress.say, plots_to=out if plots else None)
    print(f"report: {page.resolve()}", flush=True)
    return EXIT_OK if not failed else EXIT_PLAN_FAILED


def register(sub: argparse._SubParsersAction) -> None:
    bench = sub.add_parser(
        "bench", help=command_help("bench"),
        description="Defaults reproduce the source's experiment: v1-v5 x {opm, baseline} x "
                    "10 trials. Results go to OUT/trials.csv (appended as trials finish), "
                    "OUT/summary.csv|md, plots and the report page OUT/report.html (see "
                    "`cramlite report`; its path is the last line printed). Rerunning with "
                    "the same --out resumes: "
                    "trials are matched by setup name and content hash, plan, strategy, "
                    "trial and seed (a failed trial, a Timeout too, is a result: it is not "
                    "run again; to retry one, delete its row from trials.csv or use a new "
                    "--out); a folder holding another setup of the same name is "
                    "refused, and so is a folder another bench is writing into. Every setup "
                    "is checked before the first trial. Exit code 0: every trial succeeded, "
                    "1: some failed (Timeout, WorkerDied and plan failures are rows too), "
                    "2: bad arguments, 130: interrupted (Ctrl-C), 143: terminated (SIGTERM).")
    bench.add_argument("--setups", default="v1,v2,v3,v4,v5",
                       help="comma-separated setup names or paths (default v1..v5)")
    bench.add_argument("--strategies", default="opm,baseline",
                       help="comma-separated strategy names, each once (default opm,baseline; "
                            "see `cramlite strategies`; package.module:Class works too)")
    bench.add_argument("--trials", type=int_in_range(1, f"a whole number in [1, {MAX_TRIALS}]",
                                                     MAX_TRIALS), default=10,
                       help="trials per setup and strategy (default 10)")
    bench.add_argument("--seed", type=seed_int, default=0,
                       help="batch seed; each trial's seed derives from it, the setup and "
                            "the trial index (default 0)")
    bench.add_argument("--workers", type=workers_int, default=None,
                       help="local worker processes (default: number of CPUs, at most "
                            f"{MAX_WORKERS_PER_CPU} per CPU); with --scheduler, half the "
                            "number of trials kept in flight (default: the cluster's number "
                            "of worker processes)")
    bench.add_argument("--executor", choices=EXECUTORS, default="local",
                       help="local process pool (default) or Dask (pip install "
                            "'cramlite[dask]'); any Dask worker works, threads or not: each "
                            "process runs one trial at a time")
    bench.add_argument("--scheduler", metavar="ADDRESS",
                       help="Dask scheduler address, e.g. tcp://HOST:8786 (default: a local "
                            "Dask cluster)")
    bench.add_argument("--trial-timeout", type=positive_float, default=DEFAULT_TRIAL_TIMEOUT_S,
                       metavar="SECONDS",
                       help="a trial running longer is recorded as Timeout and its local "
                            "worker replaced (default 300; on Dask counted from submission)")
    bench.add_argument("--all-orders", action="store_true",
                       help="add every permutation of each setup's items as fixed-order "
                            f"trials (n! per setup; at most {MAX_ALL_ORDERS_ITEMS} items)")
    bench.add_argument("--random-setups", type=whole_number(1, 100_000), default=None,
                       metavar="N",
                       help="add N random setups (saved under OUT/setups)")
    bench.add_argument("--plan", default="set-table", help=PLAN_HELP)
    bench.add_argument("--reference", metavar="STRATEGY",
                       help="the strategy the paired tests compare every other with (one of "
                            "--strategies; default baseline if it runs, else the first)")
    bench.add_argument("--backend", help=BACKEND_HELP)
    bench.add_argument("--inject", metavar="KIND=P,...", help=INJECT_HELP + " (part of "
                       "each trial's key: a resume runs only the same injection)")
    bench.add_argument("--carry", default="1", metavar="N[,N]",
                       help=CARRY_HELP.replace("a plan option, default 1", "a plan option "
                       "and part of each trial's key; 1,2 runs every trial with each and the "
                       "report compares two hands with one; default 1"))
    bench.add_argument("--backends", dest="backends_list", metavar="A,B",
                       help="run every trial on each of these backends (the report puts "
                            "them side by side)")
    bench.add_argument("--out", default="results", help="results folder (default results)")
    bench.add_argument("--no-plots", action="store_true",
                       help="skip the PNG plots (and the report's pictures and replays: it "
                            "has tables only; `cramlite report OUT` draws them later)")
    bench.add_argument("--traces", action="store_true",
                       help="write each trial's trace to OUT/traces/SETUP-PLAN-STRATEGY-TRIAL-HASH"
                            ".jsonl (the name made safe: a slug and a hash of the full "
                            "names; replay them with `cramlite replay`)")
    bench.set_defaults(func=cmd_bench)
