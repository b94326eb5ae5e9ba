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
