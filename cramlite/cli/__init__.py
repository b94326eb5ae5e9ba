"""The `cramlite` command line. User mistakes end with one line on stderr and exit 2.

Commands are registered lazily: `COMMANDS` (in `cli.common`) names each command, its
module and its one-line help, and only the module of the command being run is imported.
So `cramlite --help`, `cramlite strategies` and `cramlite order` load neither numpy nor
the simulator, and start in a few tens of milliseconds.
"""

from __future__ import annotations

import argparse
import atexit
import importlib
import os
import sys
import threading
from collections.abc import Callable, Sequence
from typing import NoReturn

from cramlite import __version__
from cramlite.cli.common import (
    COMMANDS,
    EXIT_BAD_INPUT,
    EXIT_BROKEN_PIPE,
    Parser,
    show_ranges,
)
from cramlite.errors import UserInputError, bounded_text


def _selected(argv: Sequence[str]) -> str | None:
    """The command named on the command line (the first word that is not an option)."""
    for word in argv:
        if not word.startswith("-"):
            return word
    return None


def build_parser(argv: Sequence[str] | None = None, full: bool = False) -> argparse.ArgumentParser:
    """The parser; only the selected command's module is imported, unless `full`."""
    argv = sys.argv[1:] if argv is None else argv
    selected = _selected(argv)
    parser = Parser(prog="cramlite",
                    description="A lightweight, ROS-free robot plan executive. "
                                "`cramlite COMMAND --help` describes each command.")
    parser.add_argument("--version", action="version", version=f"cramlite {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser,
                                metavar="COMMAND")
    registered: set[str] = set()
    for name, (module, help_text) in COMMANDS.items():
        if module in registered:
            continue
        if full or COMMANDS.get(selected or "", ("",))[0] == module:
            importlib.import_module(module).register(sub)
            registered.add(module)
        else:
            sub.add_parser(name, help=help_text, add_help=False)
    for command in registered_parsers(sub):
        show_ranges(command)
    return parser


def registered_parsers(sub: argparse._SubParsersAction) -> list[argparse.ArgumentParser]:
    """The commands' parsers (each once: a command may have an alias)."""
    return list({id(p): p for p in sub.choices.values()}.values())


def main(argv: Sequence[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        parser = build_parser(argv)
        args, unknown = parser.parse_known_args(argv)
        if unknown:  # (told by the command's parser, so the message names the command)
            _command_parser(parser, args.command).error(
                f"unrecognized arguments: {' '.join(unknown)}")
        func: Callable[[argparse.Namespace], int] = args.func
        return func(args)
    except UserInputError as exc:
        command = getattr(locals().get("args"), "command", None)
        text = one_line(str(exc))
        print(f"cramlite {command}: error: {text}" if command else f"cramlite: error: {text}",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("cramlite: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. `cramlite order ... | head -c 10`: end quietly
        _silence_stdout()
        return EXIT_BROKEN_PIPE


def _command_parser(parser: argparse.ArgumentParser, command: str,
                    ) -> argparse.ArgumentParser:
    """The parser of `command` (the top-level one if there is none)."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction) and command in action.choices:
            return action.choices[command]
    return parser


def one_line(text: str) -> str:
    """A message as one line (a plugin's exception text may hold several): its lines
    joined by " / ", and cut to 2000 characters."""
    return bounded_text(" / ".join(p.strip() for p in text.splitlines() if p.strip()), 2000)


def _silence_stdout() -> None:
    """Point stdout at /dev/null, so the interpreter's final flush does not complain."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):
        pass


def console() -> NoReturn:
    """The console script: `main`, then an exit that skips the interpreter's teardown.

    Freeing the modules of Pinocchio, coal, OMPL and PyBullet one object at a time takes
    40-50 ms of a 0.8 s `cramlite run v1`. What a normal exit does that matters is kept:
    the functions registered with `atexit` run (a plan's or a library's: logging flushes
    its handlers, temporary folders are removed, a pool's workers are ended; once a user's
    plan, strategy or backend is loaded, every file still open is flushed: a plan's log it
    never closed; cramlite closes its own), and stdout and stderr are flushed. Where a
    thread that is not a daemon is still running (it would be waited for), or `main`
    raises, the exit is the normal one.
    """
    code = main()
    code = 0 if code is None else code  # (as `sys.exit(None)` would)
    if not isinstance(code, int) or _others_running() or not hasattr(atexit,
                                                                       "_run_exitfuncs"):
        sys.exit(code)
    atexit._run_exitfuncs()  # (what `sys.exit` would run before the teardown; with a
    # user's code loaded, this flushes the files it left open: `plugins.user_code`)
    for stream in (sys.stdout, sys.stderr):
        if stream is None:  # (started with the stream closed: `cramlite ... >&-`)
            continue
        try:
            stream.flush()
        except (OSError, ValueError):  # (a closed pipe: nothing more can reach it)
            if stream is sys.stdout and code == 0:
                code = EXIT_BROKEN_PIPE
    os._exit(code)


def _others_running() -> bool:
    """Whether a thread other than this one that is not a daemon is alive."""
    current = threading.current_thread()
    return any(t is not current and not t.daemon and t.is_alive()
               for t in threading.enumerate())


if __name__ == "__main__":
    console()
