"""Shared pieces of the command line: exit codes, argument types, small helpers."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable

from cramlite.errors import UserInputError

EXIT_OK, EXIT_PLAN_FAILED, EXIT_BAD_INPUT = 0, 1, 2


class Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2, as for every user mistake
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


def parse_params(text: str | None) -> dict[str, float]:
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



def progress_bar(total: float, desc: str):
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="ep", disable=not sys.stderr.isatty(),
                leave=False, dynamic_ncols=True)


def strategy_checked(name: str, **kwargs) -> None:
    from cramlite.strategies import StrategyError, make_strategy

    try:
        make_strategy(name, **kwargs)
    except StrategyError as exc:
        raise UserInputError(str(exc), field="--strategy") from None



def comma_list(text: str) -> list[str]:
    return [part.strip() for part in text.split(",") if part.strip()]



def int_at_least(minimum: int, wording: str) -> Callable[[str], int]:
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


positive_int = int_at_least(1, "a positive integer")
non_negative_int = int_at_least(0, "a whole number >= 0")
