"""The `cramlite` command line. User mistakes end with one line on stderr and exit 2."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence

from cramlite.cli import bench, evaluation, learning, ordering, replay, trials
from cramlite.cli.common import EXIT_BAD_INPUT, Parser
from cramlite.errors import UserInputError


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(prog="cramlite", description="A lightweight, ROS-free robot plan executive.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    for module in (trials, replay, ordering, evaluation, learning, bench):
        module.register(sub)
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
