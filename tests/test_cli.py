"""The command line as a package: version, `python -m`, help for every command and
option, quick commands that import only what they need, the README's command table."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from importlib import metadata

import pytest

import cramlite
from cramlite.cli import build_parser
from cramlite.cli.common import COMMANDS
from tests.conftest import ROOT, run_cli

#: Modules a quick command must not import (heavy, or not needed to answer it).
HEAVY = ("numpy", "multiprocessing", "concurrent.futures.process", "rapidfuzz", "scipy",
         "pybullet", "pinocchio", "ompl", "matplotlib", "distributed", "yaml", "tqdm",
         "PIL")
#: A 5-item request without ties (ties need the numpy generator).
REQUEST = {"robot": [-0.5, -1.8, 0.0], "params": {"mid_k": 0.3, "c": 1.7}, "items": [
    {"name": "spoon", "position": [1.45, 0.35, 0.85]},
    {"name": "breakfast-cereal", "position": [-0.85, 1.75, 0.86]},
    {"name": "milk", "position": [1.45, -0.15, 0.85]},
    {"name": "cup", "position": [1.45, 0.85, 0.85]},
    {"name": "bowl", "position": [1.45, -0.65, 0.85], "category": "mid"}]}


def test_version_matches_the_installed_distribution() -> None:
    result = run_cli("--version")
    assert result.returncode == 0
    assert result.stdout.strip() == f"cramlite {cramlite.__version__}"
    assert cramlite.__version__ == metadata.version("cramlite")


def test_python_dash_m_and_the_console_script_agree() -> None:
    script = ROOT / ".venv" / "bin" / "cramlite"
    via_m = run_cli("strategies")
    assert via_m.returncode == 0 and via_m.stdout.startswith("opm ")
    if script.exists():
        direct = subprocess.run([str(script), "strategies"], capture_output=True, text=True)
        assert direct.stdout == via_m.stdout


def _options(parser: argparse.ArgumentParser) -> list[str]:
    return [s for action in parser._actions for s in action.option_strings
            if s.startswith("--") and s != "--help"]


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser([], full=True)
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def test_every_command_is_in_the_table_with_the_same_help() -> None:
    parser = build_parser([], full=True)
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    helps = {action.dest: action.help for action in sub._choices_actions}
    assert list(helps) == list(COMMANDS)
    for name, (_, help_text) in COMMANDS.items():
        assert helps[name] == help_text, name


@pytest.mark.parametrize("command", list(COMMANDS))
def test_help_of_every_command_describes_every_option(command: str) -> None:
    result = run_cli(command, "--help")
    assert result.returncode == 0, result.stderr
    text = result.stdout
    for option in _options(_subparsers()[command]):
        assert option in text, f"{command} --help does not mention {option}"
    for action in _subparsers()[command]._actions:
        if action.option_strings and action.help != argparse.SUPPRESS:
            assert action.help, f"{command} {action.option_strings} has no help"


def test_show_help_lists_every_shipped_setup() -> None:
    text = run_cli("show", "--help").stdout
    for name in ("v1", "v2", "v3", "v4", "v5", "unreachable"):
        assert name in text


def _loaded_by(args: list[str], stdin: str = "") -> list[str]:
    code = (f"import sys\nfrom cramlite.cli import main\ntry:\n    main({args!r})\n"
            "except SystemExit:\n    pass\nsys.stdout.flush()\n"
            f"print('LOADED', sorted(m for m in {HEAVY!r} if m in sys.modules), "
            "file=sys.stderr)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            input=stdin, cwd=ROOT, timeout=120)
    line = next(x for x in result.stderr.splitlines() if x.startswith("LOADED"))
    return eval(line[len("LOADED "):])  # a list literal printed above


@pytest.mark.parametrize("args", [["--help"], ["--version"], ["strategies"], ["order", "-"],
                                  ["order", "--help"], ["show", "--help"], ["run", "--help"],
                                  ["bench", "--help"], ["bogus"]])
def test_quick_commands_import_only_what_they_need(args: list[str]) -> None:
    loaded = _loaded_by(args, stdin=json.dumps(REQUEST))
    print(args, loaded)
    assert loaded == []


def test_order_serve_imports_no_numpy_for_tie_free_requests() -> None:
    lines = "\n".join([json.dumps(REQUEST)] * 3 + ["{bad"]) + "\n"
    assert _loaded_by(["order", "--serve"], stdin=lines) == []


def test_the_command_reference_is_what_the_parsers_say() -> None:
    """docs/commands.md is generated from the parsers (python -m cramlite.cli.reference):
    an option added, renamed or explained anew shows there."""
    from cramlite.cli.reference import command_reference

    text = (ROOT / "docs" / "commands.md").read_text()
    assert text == command_reference(), "regenerate: python -m cramlite.cli.reference " \
                                        "> docs/commands.md"
    # (a description laid out by hand keeps its layout: the request of `order`)
    assert '```text\n{"robot": [x, y, z],' in text
    for name, parser in _subparsers().items():
        assert f"## `cramlite {name}`" in text
        for option in _options(parser):
            assert option in text.split(f"## `cramlite {name}`")[1].split("\n## ")[0]


def test_readme_points_to_the_reference_and_global_options() -> None:
    text = (ROOT / "README.md").read_text()
    assert "docs/commands.md" in text and "--help" in text and "python -m cramlite" in text


@pytest.mark.parametrize("args", [["run", "v1", "--stratgy", "opm"], ["strategies", "--x"],
                                  ["run", "v1", "extra"]])
def test_an_unknown_option_is_named_with_its_command(args: list[str]) -> None:
    done = run_cli(*args)
    assert done.returncode == 2
    assert done.stderr.strip() == f"cramlite {args[0]}: error: unrecognized arguments: " \
                                  f"{' '.join(args[2:] if args[0] == 'run' else args[1:])}"
