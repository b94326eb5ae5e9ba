"""`cramlite strategies` and `cramlite order` (the ordering service)."""

from __future__ import annotations

import argparse
import sys

from cramlite.cli.common import EXIT_OK
from cramlite.errors import UserInputError


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



def register(sub: argparse._SubParsersAction) -> None:
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
