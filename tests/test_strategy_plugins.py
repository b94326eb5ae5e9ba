"""Third-party strategies: `module:Class` and the `cramlite.strategies` entry-point group."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from cramlite.strategies import StrategyError, available_strategies, make_strategy
from tests.conftest import run_cli

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
