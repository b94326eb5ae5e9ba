"""The command reference (docs/commands.md), generated from the argparse parsers.

`python -m cramlite.cli.reference > docs/commands.md` writes it; a test checks the file is
what the parsers say, so the reference cannot drift from the command line.
"""

from __future__ import annotations

import argparse
import textwrap

from cramlite.cli import build_parser
from cramlite.cli.common import COMMANDS

HEADER = """# Command reference

Generated from the command line's own parsers (`python -m cramlite.cli.reference >
docs/commands.md`; a test keeps it in sync). `cramlite COMMAND --help` prints the same.
Every command exits with 0 when done, 1 when the plan failed or a check found something,
2 on bad input (one line on stderr naming the file, field or value), 130/143 when
interrupted and 141 when its output was closed early.
"""


def _usage(name: str, parser: argparse.ArgumentParser) -> str:
    usage = parser.format_usage().strip()
    usage = usage.removeprefix("usage: ")
    return "\n".join(textwrap.wrap(" ".join(usage.split()), 88,
                                   subsequent_indent="    ", break_on_hyphens=False))


def _option(action: argparse.Action) -> str:
    if action.option_strings:
        names = ", ".join(f"`{s}`" for s in action.option_strings)
        if action.nargs != 0 and action.metavar is not None:
            names += f" `{action.metavar}`"
        elif action.nargs != 0 and action.choices:
            names += " `{" + ",".join(map(str, action.choices)) + "}`"
        elif action.nargs != 0:
            names += f" `{action.dest.upper()}`"
    else:
        names = f"`{action.metavar or action.dest.upper()}`"
    help_text = " ".join((action.help or "").split())
    if "%(default)" in help_text:
        help_text = help_text % {"default": action.default}
    return f"| {names} | {help_text.replace('|', chr(92) + '|')} |"


def command_reference() -> str:
    parser = build_parser([], full=True)
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    parts = [HEADER]
    for name in COMMANDS:
        command = sub.choices[name]
        summary = COMMANDS[name][1]
        parts.append(f"## `cramlite {name}`\n\n{summary[0].upper()}{summary[1:]}.\n")
        parts.append(f"```text\n{_usage(name, command)}\n```\n")
        if command.description:
            parts.append(_description(command))
        rows = [_option(a) for a in command._actions
                if a.help != argparse.SUPPRESS and "--help" not in a.option_strings]
        if rows:
            parts.append("| argument | what it does |\n| --- | --- |\n" + "\n".join(rows) + "\n")
    return "\n".join(parts)


def _description(command: argparse.ArgumentParser) -> str:
    """A command's description as Markdown: prose joined into paragraphs; where the
    parser keeps its layout (a raw description), its indented blocks as code blocks (the
    request layout of `order` was one unreadable paragraph)."""
    text = command.description or ""
    if not issubclass(command.formatter_class, argparse.RawDescriptionHelpFormatter):
        return " ".join(text.split()) + "\n"
    out = []
    for block in text.strip("\n").split("\n\n"):
        lines = block.split("\n")
        if all(line.startswith(" ") for line in lines if line.strip()):
            out.append("```text\n" + textwrap.dedent(block).strip("\n") + "\n```")
        else:
            out.append(" ".join(block.split()))
    return "\n\n".join(out) + "\n"


if __name__ == "__main__":
    print(command_reference(), end="")
