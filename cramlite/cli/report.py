"""`cramlite report DIR`: the bench report page, (re)built from a results folder."""

from __future__ import annotations

import argparse
import sys

from cramlite.cli.common import EXIT_OK, command_help, whole_number


def speed(text: str) -> float:
    """An argparse type: a replay speed-up in [1, 100]."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 1 <= value <= 100:
        raise argparse.ArgumentTypeError(f"expected a number from 1 to 100, got {text!r}")
    return value


def cmd_report(args: argparse.Namespace) -> int:
    from cramlite.report import build_report

    def say(message: str) -> None:
        print(message, file=sys.stderr, flush=True)

    page = build_report(args.folder, figures=not args.no_plots, max_replays=args.max_replays,
                        speed=args.speed, say=say)
    print(f"wrote {page}")
    return EXIT_OK


def register(sub: argparse._SubParsersAction) -> None:
    from cramlite.report.build import DEFAULT_MAX_REPLAYS
    from cramlite.report.replays import DEFAULT_SPEED

    report = sub.add_parser(
        "report", help=command_help("report"),
        description="Writes DIR/report.html, one page with no network access needed (its "
                    "pictures are in DIR/report/): run parameters and library versions, the "
                    "summary table, the statistical tests, the box plots; per setup a "
                    "top-down map with each strategy's driven paths and fetch order; per "
                    "trial of interest (the first of each setup and strategy, every failed "
                    "one) a timeline of its task tree, its steps and, when the bench wrote "
                    "traces, its replay; with --all-orders, where each strategy falls among "
                    "all orders. It shows the trials of the last bench command run into "
                    "DIR (as that command's summary does; the page says how many others "
                    "trials.csv holds: rerun such a command for its report). Works on a "
                    "folder a bench is still filling or that was interrupted. Exit code 0: "
                    "written, 2: not a bench folder or a malformed file (named).")
    report.add_argument("folder", metavar="DIR",
                        help="a results folder written by `cramlite bench --out DIR`")
    report.add_argument("--max-replays", type=whole_number(0, 10_000),
                        default=DEFAULT_MAX_REPLAYS,
                        metavar="N",
                        help=f"draw at most N replay GIFs of traced trials (default "
                             f"{DEFAULT_MAX_REPLAYS}; 0: none); each takes a few seconds and "
                             "is kept for the next build")
    report.add_argument("--speed", type=speed, default=DEFAULT_SPEED,
                        help=f"replays play this many times faster than the robot moved "
                             f"(default {DEFAULT_SPEED:g}, 1-100)")
    report.add_argument("--no-plots", action="store_true",
                        help="tables only: no plots, maps or timelines (quick; also what "
                             "you get without matplotlib)")
    report.set_defaults(func=cmd_report)
