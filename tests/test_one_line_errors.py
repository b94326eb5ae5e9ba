"""A mistake in a user's own code reaches the command line as one line (#29 finding 7):
a strategy whose exception text has several lines, a module that raises on import."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import run_cli

RAISES_IN_CHOOSE = '''
from cramlite import Strategy


class Cls(Strategy):
    name = "raiser"
    uses_params = False

    def choose(self, remaining, agent):
        raise RuntimeError("first line\\nsecond line\\n  third line")
'''
RAISES_ON_IMPORT = 'raise ValueError("boom\\nline two")\n'


@pytest.mark.parametrize("source, expected", [
    (RAISES_IN_CHOOSE, "raised RuntimeError: first line / second line / third line"),
    (RAISES_ON_IMPORT, "ValueError: boom / line two"),
])
def test_a_multi_line_exception_of_a_plugin_is_one_line(tmp_path: Path, source: str,
                                                        expected: str) -> None:
    (tmp_path / "s.py").write_text(source)
    for command in (["run", "v1", "--backend", "kinematic"], ["evaluate", "table-setting"]):
        result = run_cli(*command, "--strategy", "./s.py:Cls", cwd=tmp_path)
        lines = result.stderr.strip().splitlines()
        assert result.returncode == 2 and len(lines) == 1, result.stderr
        assert expected in lines[0] and "--strategy" in lines[0]


def test_a_failure_says_each_thing_it_tried_once_with_how_often() -> None:
    """(#27: an ObjectUnreachable of 755 characters repeated 'could not put it down at the
    goal' nine times.)"""
    from cramlite.designators.failures import ObjectUnreachable

    failure = ObjectUnreachable("no base pose reaches it", obj="cup",
                                tried=["right arm top grasp: could not put it down"] * 9
                                + ["left arm: out of reach"])
    assert str(failure) == ("cup: no base pose reaches it (tried: right arm top grasp: could "
                            "not put it down (9 times); left arm: out of reach)")
    assert len(failure.as_dict()["tried"]) == 10  # (the row keeps every attempt)


@pytest.mark.parametrize("args, expected", [
    (["run", "v1", "--params", "c=2"], "strategy 'baseline' takes no parameters"),
    (["run", "v1", "--strategy", "nearest", "--params", "c=2"],
     "strategy 'nearest' takes no parameters"),
    (["evaluate", "table-setting", "--strategy", "baseline", "--params", "c=2"],
     "strategy 'baseline' takes no parameters"),
    (["run", "v1", "--strategy", "opm", "--params", "c=1.7,c=2"], "c is given twice"),
])
def test_parameters_a_strategy_would_ignore_are_refused(args: list[str],
                                                        expected: str) -> None:
    """--params for a strategy without parameters, or one given twice, is a mistake to
    say, not to run past (the run would not be the one asked for)."""
    result = run_cli(*args)
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1, result.stderr
    assert "--params" in lines[0] and expected in lines[0], lines[0]


def test_a_strategy_without_a_name_is_named_by_its_file_and_class(tmp_path: Path) -> None:
    (tmp_path / "s.py").write_text("from cramlite import Strategy\n\n\n"
                                   "class ReturnsNone(Strategy):\n    uses_params = False\n\n"
                                   "    def choose(self, remaining, agent):\n"
                                   "        return None\n")
    result = run_cli("run", "v1", "--strategy", "./s.py:ReturnsNone", "--backend",
                     "kinematic", cwd=tmp_path)
    assert result.returncode == 2
    assert f"strategy {tmp_path / 's.py'}:ReturnsNone returned None" in result.stderr, \
        result.stderr
