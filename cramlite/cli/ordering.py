"""`cramlite strategies` and `cramlite order` (the ordering service)."""

from __future__ import annotations

import argparse
import sys

from cramlite.cli.common import EXIT_OK, command_help, strategy_checked
from cramlite.errors import UserInputError
from cramlite.file_limits import checked_file

ORDER_DESCRIPTION = """\
Answers ordering requests: which item to fetch next, the cost of each, and the whole
order. A request is one JSON object:

  {"robot": [x, y, z],                       where the agent stands (required)
   "items": [{"name": "bowl",                unique names (required)
              "position": [x, y, z],         (required)
              "category": "mid",             strong | mid | food | none -> k from params
              "k": 0.3,                      or k itself, in [0, 10]
              "contained": false,            in closed storage -> c from params
              "c": 1.7,                      or c itself, in (0, 1000]
              "then_at": [x, y, z]}, ...],   where the agent stands after this item
   "strategy": "opm",                        a registered strategy (see `strategies`)
   "params": {"strong_k": 0.2, "mid_k": 0.3, "food_k": 1.2, "c": 1.7},
   "dims": "xy",                             x, y, z, xy, xz, yz or xyz
   "form": "power",                          power (Eq. 3.1), additive or product
   "weights": [wx, wy, wz] | "span",         axis weights (Eq. 3.5/3.6), each in [0, 1000]
   "seed": 0,                                tie-breaks, an integer in [0, 2^64 - 1]
   "then_at": [x, y, z],                     default then_at of every item
   "full_order": true,                       false: next and costs only
   "capacity": 2,                            items carried together (1-16): adds "batch"
   "id": "r1"}                               echoed in the reply

The reply is one line of strict JSON: {"id", "next", "costs": {name: cost}, "order"},
and with "capacity" also "batch": the items to carry together next, in fetch order.
Coordinates must lie within +-1e6 m. Limits: 100000 items per request; the full order
(each step repeats the query, so it is quadratic) for at most 200 items: above that,
send "full_order": false, which answers in time linear in the number of items.

Without --serve, one request is read from FILE or stdin, the reply printed, and a bad
request ends with one line on stderr and exit code 2. With --serve, requests are read
one per line from stdin until end of input, and each gets one reply line (flushed); a
bad line gets {"error": "FIELD: what was expected", "field": "FIELD"} and the service
goes on."""


def cmd_strategies(args: argparse.Namespace) -> int:
    from cramlite.strategies import available_strategies

    listing = available_strategies()
    width = max(map(len, listing))
    for name, summary in listing.items():
        print(f"{name:<{width}}  {summary}")
    return EXIT_OK


def cmd_order(args: argparse.Namespace) -> int:
    from cramlite.strategies.service import MAX_REQUEST_BYTES, answer_text, encode, serve

    strategy_checked(args.strategy)
    if args.serve:
        if args.request != "-":
            raise UserInputError("--serve reads requests from stdin; give no FILE",
                                 field="--serve")

        def report(exc: BaseException) -> None:
            print(f"cramlite order: internal error: {type(exc).__name__}: {exc}",
                  file=sys.stderr, flush=True)

        serve(sys.stdin.buffer, sys.stdout, args.strategy, report)
        return EXIT_OK
    source = "<stdin>" if args.request == "-" else args.request
    try:
        if args.request == "-":
            data = sys.stdin.buffer.read(MAX_REQUEST_BYTES + 1)
        else:
            checked_file(args.request, "request")
            with open(args.request, "rb") as handle:
                data = handle.read(MAX_REQUEST_BYTES + 1)
    except OSError as exc:
        raise UserInputError(f"cannot read request ({exc.strerror})", source=source) from None
    if len(data) > MAX_REQUEST_BYTES:
        raise UserInputError(f"longer than {MAX_REQUEST_BYTES} bytes", source=source)
    print(encode(answer_text(data, source, args.strategy)))
    return EXIT_OK


def register(sub: argparse._SubParsersAction) -> None:
    strategies = sub.add_parser(
        "strategies", help=command_help("strategies"),
        description="Lists the registered strategies: the built-in ones and those that "
                    "installed packages register under the entry-point group "
                    "cramlite.strategies. Commands that take --strategy also accept "
                    "package.module:Class and path/to/file.py:Class (a module in the "
                    "current folder is found without PYTHONPATH).")
    strategies.set_defaults(func=cmd_strategies)

    order = sub.add_parser("order", help=command_help("order"), description=ORDER_DESCRIPTION,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    order.add_argument("request", nargs="?", default="-", metavar="FILE",
                       help="JSON request file, or - for stdin (default)")
    order.add_argument("--serve", action="store_true",
                       help="answer one request per line of stdin until end of input")
    order.add_argument("--strategy", default="opm",
                       help="strategy for requests that name none (default opm); may also "
                            "be package.module:Class, which requests themselves may not name")
    order.set_defaults(func=cmd_order)
