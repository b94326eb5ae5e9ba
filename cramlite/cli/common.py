"""Shared pieces of the command line: the command table, exit codes, argument types.

Importing this module loads no implementation module (no numpy, no simulator), so that
`cramlite --help` and quick commands start quickly.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

from cramlite.errors import UserInputError

EXIT_OK, EXIT_PLAN_FAILED, EXIT_BAD_INPUT = 0, 1, 2
#: The exit code of a process whose output pipe was closed (as if killed by SIGPIPE).
EXIT_BROKEN_PIPE = 141

#: Every command: the module that registers it and its one-line help. A module is
#: imported only to run (or describe) one of its own commands.
COMMANDS: dict[str, tuple[str, str]] = {
    "show": ("cramlite.cli.trials", "draw a setup headless into a PNG"),
    "run": ("cramlite.cli.trials", "run one trial of a plan in a setup (headless)"),
    "plans": ("cramlite.cli.trials", "list the plans by name (built-in and plugins)"),
    "strategies": ("cramlite.cli.ordering", "list the ordering strategies by name"),
    "order": ("cramlite.cli.ordering",
              "answer JSON ordering requests (the OPM service without ROS)"),
    "evaluate": ("cramlite.cli.evaluation", "score a strategy against human sequences"),
    "fit": ("cramlite.cli.evaluation", "grid-search a strategy's parameters (Table 3.4)"),
    "simulate": ("cramlite.cli.evaluation",
                 "synthetic episodes drawn from a strategy (parameter recovery)"),
    "replay": ("cramlite.cli.replay",
               "replay a trace (cramlite run --trace): GIF, GUI or collision check"),
    "train": ("cramlite.cli.learning", "train a learned ordering strategy (RNN, NN, CPT)"),
    "compare": ("cramlite.cli.learning",
                "compare strategies on human sequences (Wilcoxon, Figure 3.18)"),
    "reproduce": ("cramlite.cli.reproduce",
                  "rebuild every table the README claims, beside the published ones"),
    "bench": ("cramlite.cli.bench",
              "run many trials (setups x strategies x trials) and summarise them"),
    "report": ("cramlite.cli.report",
               "the bench report page (DIR/report.html) from a results folder"),
}
#: Image files `show --out` and `run --image` can write (by suffix).
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")


def command_help(name: str) -> str:
    return COMMANDS[name][1]


INJECT_HELP = ("make executions fail now and then, as a robot's would, to exercise "
               "recovery: grasp=P (the item slips as the fingers close), navigate=P (a "
               "drive is refused before the base moves), detect=P (the camera sees nothing), "
               "probabilities per attempt, drawn from a stream seeded by the trial's seed")
BACKEND_HELP = ("what executes (and draws) it: pybullet, mujoco, kinematic, recording or a "
                "plugin's (default: pybullet if it is installed, else mujoco if it is, "
                "else kinematic)")


def chosen_backend(name: str | None) -> str:
    """The backend asked for (checked: installed here), or the default one."""
    from cramlite.backends import check_backend, default_backend

    return check_backend(name) if name else default_backend()


class Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2, as for every user mistake
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


def parse_params(text: str | None) -> dict[str, float]:
    """`--params strong_k=0.2,c=1.7` -> {name: value}; every value is range-checked."""
    from cramlite.strategies.base import parameter_problem
    from cramlite.strategies.candidates import OPMParams

    params: dict[str, float] = {}
    for part in filter(None, (text or "").split(",")):
        name, sep, value = part.partition("=")
        name = name.strip()
        if not sep or name not in OPMParams.names():
            raise UserInputError(f"expected NAME=VALUE with NAME one of "
                                 f"{', '.join(OPMParams.names())}, got {part!r}",
                                 field="--params")
        try:
            number = float(value)
        except ValueError:
            raise UserInputError(f"expected a number for {name}, got {value!r}",
                                 field="--params") from None
        problem = parameter_problem(name, number)
        if problem:
            raise UserInputError(f"{name}: {problem}", field="--params")
        if name in params:
            raise UserInputError(f"{name} is given twice ({params[name]:g} and {number:g}); "
                                 "expected each parameter once", field="--params")
        params[name] = number
    return params


def progress_bar(total: float, desc: str):
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="ep", disable=not sys.stderr.isatty(),
                leave=False, dynamic_ncols=True)


def strategy_checked(name: str, **kwargs) -> None:
    """Refuse an unknown or unusable strategy (or parameters) as a --strategy error."""
    from cramlite.strategies import StrategyError, make_strategy
    from cramlite.strategies.registry import ignores_params

    try:
        if kwargs.get("params") and ignores_params(name):
            raise UserInputError(f"strategy {name!r} takes no parameters (those of --params "
                                 "are the OPM's: e.g. --strategy opm)", field="--params")
        make_strategy(name, **kwargs)
    except StrategyError as exc:
        raise UserInputError(str(exc), field="--strategy") from None


def comma_list(text: str) -> list[str]:
    return [part.strip() for part in text.split(",") if part.strip()]


def int_in_range(minimum: int, wording: str, maximum: int | None = None,
                 ) -> Callable[[str], int]:
    """An argparse type: a whole number in [minimum, maximum] (the message names what was
    expected)."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = None
        if value is None or value < minimum or (maximum is not None and value > maximum):
            raise argparse.ArgumentTypeError(f"expected {wording}, got {text!r}")
        return value
    parse.expected = wording  # type: ignore[attr-defined]  # (shown in --help)
    return parse


def whole_number(minimum: int, maximum: int) -> Callable[[str], int]:
    """An argparse type: a whole number in [minimum, maximum]."""
    return int_in_range(minimum, f"a whole number in [{minimum}, {maximum}]", maximum)


def float_in_range(minimum: float, maximum: float, wording: str,
                   open_minimum: bool = False) -> Callable[[str], float]:
    """An argparse type: a finite number in [minimum, maximum] ((minimum, maximum] with
    `open_minimum`); the message names what was expected."""
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        low_ok = value > minimum if open_minimum else value >= minimum
        if not (math.isfinite(value) and low_ok and value <= maximum):
            raise argparse.ArgumentTypeError(f"expected {wording}, got {text!r}")
        return value
    parse.expected = wording  # type: ignore[attr-defined]  # (shown in --help)
    return parse


def show_ranges(parser: argparse.ArgumentParser) -> None:
    """Add to each option's help what values it takes, where its type says (`int_in_range`,
    `float_in_range`) and the help does not already."""
    for action in parser._actions:
        expected = getattr(action.type, "expected", None)
        if not expected or action.help in (None, argparse.SUPPRESS):
            continue
        expected = expected.split(": ", 1)[-1]  # ("a seed: a whole number ...")
        # (a help that gives the bounds its own way, "1-4096", "1 or 2", keeps its words)
        bounds = re.findall(r"\d+(?:\.\d+)?", expected)
        if all(re.search(rf"(?<![\d.]){re.escape(b)}(?![\d.])", action.help) for b in bounds):
            continue
        action.help = (f"{action.help}; {expected}" if action.help.endswith(")")
                       else f"{action.help} ({expected})")


#: Upper bounds of numeric options: far beyond any real use, low enough that no option
#: alone can make cramlite allocate gigabytes or run for years.
MAX_SEED = 2**64 - 1
MAX_REPEATS = 100_000
MAX_EPOCHS = 100_000
MAX_EPISODES = 1_000_000
MAX_WORKERS = 1024
MAX_TIMEOUT_S = 7 * 24 * 3600.0

#: A finite number of seconds > 0 (up to a week).
positive_float = float_in_range(0.0, MAX_TIMEOUT_S, f"a number of seconds > 0 and <= "
                                f"{MAX_TIMEOUT_S:g}", open_minimum=True)


def image_path(text: str) -> str:
    """An argparse type: a file name with an image suffix PIL writes."""
    if not text.lower().endswith(IMAGE_SUFFIXES) or text.endswith(("/", "\\")):
        raise argparse.ArgumentTypeError(
            f"expected an image file name ending in {', '.join(IMAGE_SUFFIXES)}, got {text!r}")
    return text


seed_int = int_in_range(0, "a seed: a whole number in [0, 2^64 - 1]", MAX_SEED)
repeats_int = whole_number(1, MAX_REPEATS)
epochs_int = whole_number(1, MAX_EPOCHS)
episodes_int = whole_number(1, MAX_EPISODES)
workers_int = whole_number(1, MAX_WORKERS)
#: --carry: items carried at once (the PR2 has two hands).
carry_int = int_in_range(1, "1 or 2 (one item per hand)", 2)
CARRY_HELP = ("how many items the set-table and clear-table plans carry at once: 1, or 2 "
              "(one per hand: the strategy chooses each batch; items in drawers or the "
              "cupboard, or bound for them, are carried alone); a plan option, default 1")


def writable_file(text: str, option: str,
                  inputs: Sequence[tuple[str, str | Path | None]] = ()) -> None:
    """Refuse, before any work, a file that could not be written at the end: a folder, a
    path under a file, a read-only place (its folders are made), or one of the command's
    own `inputs` ((what, path): the setup file, the plan file...), which it would
    overwrite."""
    target = Path(text)
    if target.is_dir():
        raise UserInputError("is a folder; expected the name of a file to write",
                             source=text, field=option)
    for what, path in inputs:
        if path is not None and Path(path).is_file() and target.is_file() and \
                os.path.samefile(path, target):
            raise UserInputError(f"is the {what} this command reads; expected another file "
                                 "to write (it would be overwritten)", source=text,
                                 field=option)
    under = next((parent for parent in target.parents if parent.is_file()), None)
    if under is not None:
        raise UserInputError(f"is under a file ({under}); expected a file in a folder",
                             source=text, field=option)
    existed = target.exists()
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        with target.open("a", encoding="utf-8"):
            pass
    except OSError as exc:
        raise UserInputError(f"cannot write it ({exc.strerror or exc})", source=text,
                             field=option) from None
    if not existed:
        target.unlink()  # (only probed: the command writes it when it is done)


def writable_folder(text: str, option: str = "--out") -> Path:
    """A folder to write into, made now (with its parents): refuses a file, a path under
    a file, a read-only place."""
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise UserInputError("expected a folder (or a new path), got an existing file",
                             source=text, field=option)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserInputError(f"cannot make the folder ({exc.strerror or exc})", source=text,
                             field=option) from None
    return path
