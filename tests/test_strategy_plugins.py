"""Third-party strategies: `module:Class` and the `cramlite.strategies` entry-point group."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from cramlite.strategies import StrategyError, available_strategies, make_strategy
from tests.conftest import ROOT, run_cli

PLUGIN = '''
from cramlite.strategies import Strategy

class Farthest(Strategy):
    name = "farthest"
    summary = "the farthest item first"

    def choose(self, remaining, agent):
        return max(remaining, key=lambda c: self.model.distance(agent, c.position))
'''


@pytest.fixture
def plugin_path(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    (tmp_path / "my_strategies.py").write_text(PLUGIN)
    dist = tmp_path / "my_strategies-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: my-strategies\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text(
        "[cramlite.strategies]\nfarthest = my_strategies:Farthest\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    yield tmp_path
    sys.modules.pop("my_strategies", None)


REQUEST = ('{"robot": [0, 0, 0], "strategy": "%s", "items": ['
           '{"name": "near", "position": [1, 0, 0]}, {"name": "far", "position": [5, 0, 0]}]}')


def test_entry_point_plugin_is_listed_and_usable(plugin_path: Path) -> None:
    assert "farthest" in available_strategies()
    from cramlite.strategies import Candidate
    items = [Candidate("near", (1, 0, 0)), Candidate("far", (5, 0, 0))]
    assert make_strategy("farthest").choose(items, (0, 0, 0)).name == "far"
    env = {"PYTHONPATH": str(plugin_path)}
    listing = run_cli_env(["strategies"], env)
    assert "farthest" in listing.stdout
    reply = run_cli_env(["order"], env, stdin=REQUEST % "farthest")
    assert reply.returncode == 0, reply.stderr
    assert '"next": "far"' in reply.stdout


def test_module_colon_class(plugin_path: Path) -> None:
    from cramlite.strategies import Candidate
    s = make_strategy("my_strategies:Farthest")
    assert s.choose([Candidate("a", (1, 0, 0)), Candidate("b", (2, 0, 0))], (0, 0, 0)).name == "b"
    with pytest.raises(StrategyError, match="cannot load"):
        make_strategy("my_strategies:Nope")
    with pytest.raises(StrategyError, match="not a cramlite.strategies.Strategy"):
        make_strategy("pathlib:Path")


def run_cli_env(args, env, stdin=None):
    import os
    import subprocess
    full = {**os.environ, **env}
    full["PYTHONPATH"] = os.pathsep.join([env["PYTHONPATH"], str(Path(__file__).parents[1])])
    return subprocess.run([sys.executable, "-m", "cramlite", *args], capture_output=True,
                          text=True, input=stdin, env=full, timeout=120)


def test_strategies_command_lists_the_builtins() -> None:
    result = run_cli("strategies")
    assert result.returncode == 0
    names = [line.split()[0] for line in result.stdout.splitlines()]
    assert {"opm", "baseline", "random", "nearest", "opm-2step", "optimal"} <= set(names)


MISBEHAVING = '''
from cramlite.strategies import Candidate, Strategy

class Raises(Strategy):
    name = "raises"
    def choose(self, remaining, agent):
        raise KeyError("no idea")

class ReturnsNone(Strategy):
    name = "returns-none"
    def choose(self, remaining, agent):
        return None

class ReturnsStranger(Strategy):
    name = "returns-stranger"
    def choose(self, remaining, agent):
        return Candidate("teapot", (0.0, 0.0, 0.0))

class ReturnsName(Strategy):
    name = "returns-name"
    def choose(self, remaining, agent):
        return remaining[0].name

class ResetRaises(Strategy):
    name = "reset-raises"
    def reset(self, candidates, agent):
        raise RuntimeError("no reset")
    def choose(self, remaining, agent):
        return remaining[0]

class BadInit(Strategy):
    name = "bad-init"
    def __init__(self, *args, **kwargs):
        raise RuntimeError("cannot start")
    def choose(self, remaining, agent):
        return remaining[0]
'''


@pytest.fixture
def misbehaving(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    (tmp_path / "misbehaving.py").write_text(MISBEHAVING)
    monkeypatch.syspath_prepend(str(tmp_path))
    yield tmp_path
    sys.modules.pop("misbehaving", None)


@pytest.mark.parametrize(("cls", "expected"), [
    ("Raises", "raised KeyError: 'no idea'"),
    ("ReturnsNone", "returned None (NoneType); expected one of the 2 remaining candidates"),
    ("ReturnsStranger", "returned Candidate(name='teapot'"),
    ("ReturnsName", "returned 'near' (str)"),
])
def test_checked_choice_names_a_misbehaving_plugin(misbehaving: Path, cls: str,
                                                   expected: str) -> None:
    from cramlite.strategies import Candidate
    from cramlite.strategies.base import checked_choice

    strategy = make_strategy(f"misbehaving:{cls}")
    items = [Candidate("near", (1, 0, 0)), Candidate("far", (5, 0, 0))]
    with pytest.raises(StrategyError) as info:
        checked_choice(strategy, items, (0, 0, 0))
    print(info.value)
    assert f"misbehaving.{cls}" in str(info.value)
    assert expected in str(info.value)


def test_checked_choice_returns_the_remaining_candidate_itself() -> None:
    from cramlite.strategies import Candidate
    from cramlite.strategies.base import checked_choice

    items = [Candidate("near", (1, 0, 0)), Candidate("far", (5, 0, 0))]
    chosen = checked_choice(make_strategy("opm"), items, (0, 0, 0))
    assert chosen is items[0]


def test_a_plugin_whose_constructor_fails_is_named(misbehaving: Path) -> None:
    with pytest.raises(StrategyError, match=r"misbehaving.BadInit.*RuntimeError: cannot start"):
        make_strategy("misbehaving:BadInit")


@pytest.mark.parametrize(("cls", "expected"), [
    ("Raises", "raised KeyError"),
    ("ReturnsNone", "returned None"),
    ("ReturnsStranger", "returned Candidate(name='teapot'"),
    ("ResetRaises", "raised RuntimeError when reset: no reset"),
    ("BadInit", "could not be created"),
])
def test_run_with_a_misbehaving_plugin_is_one_clear_line(misbehaving: Path, cls: str,
                                                         expected: str) -> None:
    result = run_cli_env(["run", "v1", "--strategy", f"misbehaving:{cls}"],
                         {"PYTHONPATH": str(misbehaving)})
    print(result.stderr)
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1
    assert "--strategy" in lines[0] and f"misbehaving.{cls}" in lines[0]
    assert expected in lines[0]


@pytest.mark.parametrize(("cls", "expected"), [
    ("ReturnsNone", "returned None"), ("ResetRaises", "raised RuntimeError when reset")])
def test_a_user_plan_that_asks_a_misbehaving_strategy_gets_one_clear_line(
        misbehaving: Path, cls: str, expected: str) -> None:
    """(A user's plan calls strategy.choose itself, as examples/fetch_two.py does: the
    strategy it is given is checked as the built-in plans check theirs.)"""
    plan = f"{ROOT / 'examples' / 'fetch_two.py'}:fetch_two"
    result = run_cli_env(["run", "v1", "--plan", plan, "--strategy", f"misbehaving:{cls}",
                          "--backend", "kinematic"], {"PYTHONPATH": str(misbehaving)})
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr and len(result.stderr.strip().splitlines()) == 1
    assert f"misbehaving.{cls}" in result.stderr and expected in result.stderr, result.stderr


@pytest.mark.parametrize("command", ["evaluate", "compare", "fit"])
@pytest.mark.parametrize(("cls", "expected"), [
    ("Raises", "raised KeyError"),
    ("ReturnsStranger", "Candidate(name='teapot'"),
    ("ResetRaises", "raised RuntimeError when reset: no reset"),
])
def test_scoring_a_misbehaving_plugin_stops_with_one_clear_line(
        misbehaving: Path, tmp_path: Path, command: str, cls: str, expected: str) -> None:
    """Not an episode skipped per bug (every one would be): one line, exit 2."""
    name = f"misbehaving:{cls}"
    args = {"evaluate": ["evaluate", "table-setting", "--strategy", name],
            "compare": ["compare", "table-setting", "--strategies", f"opm,{name}"],
            "fit": ["fit", "table-setting", "--strategy", name, "--workers", "1",
                    "--out", str(tmp_path / "fit")]}[command]
    result = run_cli_env(args, {"PYTHONPATH": str(misbehaving)})
    print(result.stderr[-2000:])
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    last = result.stderr.strip().splitlines()[-1]
    assert "--strateg" in last and f"misbehaving.{cls}" in last and expected in last


def test_run_optimal_with_more_than_15_items_is_the_clean_error(tmp_path: Path) -> None:
    from tests.setup_files import many_cups, write

    path = write(tmp_path, many_cups(16))
    result = run_cli("run", str(path), "--strategy", "optimal")
    print(result.stderr)
    assert result.returncode == 2
    assert result.stderr.strip() == (
        "cramlite run: error: --strategy: optimal plans exactly for at most 15 items, got 16; "
        "use opm or opm-2step for larger tasks")


def test_a_request_cannot_import_code_but_the_command_line_can(plugin_path: Path) -> None:
    env = {"PYTHONPATH": str(plugin_path)}
    request = REQUEST % "my_strategies:Farthest"
    refused = run_cli_env(["order"], env, stdin=request)
    print(refused.stderr)
    assert refused.returncode == 2
    assert "strategy" in refused.stderr and "not a registered strategy" in refused.stderr
    allowed = run_cli_env(["order", "--strategy", "my_strategies:Farthest"], env,
                          stdin=REQUEST.replace('"strategy": "%s", ', ""))
    assert allowed.returncode == 0, allowed.stderr
    assert '"next": "far"' in allowed.stdout
    with pytest.raises(StrategyError, match="not a registered strategy"):
        make_strategy("my_strategies:Farthest", registered_only=True)
    assert make_strategy("farthest", registered_only=True).name == "farthest"  # entry point
