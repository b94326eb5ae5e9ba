"""Two hands, two items (#26): batches chosen by strategies, carried one per hand, every
state checked; the ordering service's batch requests; `bench --carry 1,2`."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

from cramlite.strategies import Candidate, Strategy, StrategyCrashed, make_strategy
from cramlite.strategies.base import checked_batch
from cramlite.strategies.registry import BUILTIN
from cramlite.strategies.service import answer
from cramlite.trace.check import checker_for, object_frame, penetrations
from cramlite.trace.format import read_trace
from cramlite.trace.physics import physics_findings
from cramlite.trial import TrialRunner
from cramlite.world.setup import load_setup
from tests.conftest import run_cli

#: A hand-made task: a at 1 m, b at 2 m ahead, c 1.5 m behind; every item then goes to
#: T = (0, 1). Distances are the costs (k = c = 1).
T = (0.0, 1.0, 0.0)
ITEMS = [Candidate("a", (1.0, 0.0, 0.0), then_at=T), Candidate("b", (2.0, 0.0, 0.0), then_at=T),
         Candidate("c", (-1.5, 0.0, 0.0), then_at=T)]
ROBOT = (0.0, 0.0, 0.0)


def names(batch: list[Candidate]) -> list[str]:
    return [c.name for c in batch]


def test_the_pair_cost_on_a_hand_made_case_with_a_known_answer() -> None:
    # opm without a batch answer: the two cheapest from where the robot stands (1, 1.5)
    assert names(checked_batch(make_strategy("nearest"), ITEMS, ROBOT, 2)) == ["a", "c"]
    # opm-batch: the second seen from where the first is taken: b is 1 m from a, c 2.5 m
    assert names(checked_batch(make_strategy("nearest-batch"), ITEMS, ROBOT, 2)) == ["a", "b"]
    # each item with its own k: a at 0.8 m costs 0.8 (c: 1.5^0.1 = 1.04); from a, b costs
    # 1.2 and c 2.3^0.1 = 1.09, so opm-batch carries a and c where plain distance says b
    weighted = [Candidate("a", (0.8, 0.0, 0.0), k=1.0), Candidate("b", (2.0, 0.0, 0.0), k=1.0),
                Candidate("c", (-1.5, 0.0, 0.0), k=0.1)]
    assert names(checked_batch(make_strategy("opm-batch"), weighted, ROBOT, 2)) == ["a", "c"]
    assert names(checked_batch(make_strategy("nearest-batch"), weighted, ROBOT, 2)) == \
        ["a", "b"]
    # optimal-batch: a + b (1 + 1), then c from T (sqrt(1 + 1.5^2)) = 3.80 beats c alone
    # first (1.5 + sqrt(2) + 1 = 3.91) and every other grouping
    optimal = make_strategy("optimal-batch")
    total, trips = optimal.plan_trips(ITEMS, ROBOT, 2)
    assert [names(list(t)) for t in trips] == [["a", "b"], ["c"]]
    assert total == pytest.approx(2 + math.hypot(1.0, 1.5))
    assert names(optimal.choose_batch(ITEMS, ROBOT, 2)) == ["a", "b"]
    # with one hand it is the ordinary optimum: c alone costs 1.5, then a, then b
    assert names(optimal.choose_batch(ITEMS, ROBOT, 1)) in (["a"], ["c"])


def test_random_batch_is_seeded_and_distinct() -> None:
    draws = [names(make_strategy("random-batch", rng=7).choose_batch(ITEMS, ROBOT, 2))
             for _ in range(2)]
    assert draws[0] == draws[1] and len(set(draws[0])) == 2


class OnlyChoose(Strategy):
    """A plugin written before batches existed: it answers `choose` only."""

    name = "only-choose"

    def choose(self, remaining, agent):
        return remaining[-1]


@pytest.mark.parametrize("name", sorted(BUILTIN))
def test_every_existing_strategy_answers_a_batch_unchanged(name: str) -> None:
    strategy = make_strategy(name, rng=0)
    strategy.reset(ITEMS, ROBOT)
    batch = checked_batch(strategy, ITEMS, ROBOT, 2)
    assert len(batch) == 2 and len({c.name for c in batch}) == 2
    assert all(c in ITEMS for c in batch)


def test_a_plugin_with_only_choose_is_asked_once_per_hand() -> None:
    assert names(checked_batch(OnlyChoose(), ITEMS, ROBOT, 2)) == ["c", "b"]


def test_a_batch_that_is_not_one_of_the_remaining_items_is_refused() -> None:
    class Twice(OnlyChoose):
        def choose_batch(self, remaining, agent, capacity):
            return [remaining[0], remaining[0]]

    with pytest.raises(StrategyCrashed, match="distinct remaining candidates"):
        checked_batch(Twice(), ITEMS, ROBOT, 2)


def request(**extra) -> dict:
    return {"robot": list(ROBOT), "items": [{"name": c.name, "position": list(c.position)}
                                            for c in ITEMS], **extra}


def test_a_batch_request_to_order() -> None:
    plain = answer(request())
    batched = answer(request(capacity=2, strategy="opm-batch"))
    assert "batch" not in plain
    assert batched["next"] == plain["next"] == "a" and batched["order"] == plain["order"]
    assert batched["batch"] == ["a", "b"]
    assert answer(request(capacity=2))["batch"] == ["a", "c"]  # opm: choose per hand
    result = run_cli("order", stdin=json.dumps(request(capacity=0)))
    assert result.returncode == 2 and "capacity" in result.stderr


def _tool_pose(robot: dict[str, np.ndarray], arm: str) -> np.ndarray:
    return robot[f"{arm[0]}_gripper_tool_frame"]


@pytest.mark.slow
def test_carrying_two_delivers_both_and_the_first_stays_put_in_its_hand(tmp_path) -> None:
    trace = tmp_path / "v1.jsonl"
    with TrialRunner("v1", backend="kinematic") as runner:
        result = runner.run("opm-batch", seed=0, trace=trace, carry=2)
    assert result.success and result.carry == 2
    pairs = [t for t in result.trips if len(t) == 2]
    assert len(pairs) == 2 and sorted(sum(result.trips, [])) == sorted(result.order)
    record = read_trace(trace)
    assert not penetrations(record), "something inside something with two hands full"
    assert not physics_findings(record)
    checker = checker_for(record)
    both_full = 0
    in_hand: dict[str, list[np.ndarray]] = {}
    for state in record.states:
        if len(state["held"]) == 2:
            both_full += 1
        robot = checker.robot_frames(state)
        for name, arm in state["held"].items():
            relative = np.linalg.inv(_tool_pose(robot, arm)) @ object_frame(state["objects"][name])
            in_hand.setdefault(f"{name}/{arm}", []).append(relative)
    assert both_full > 100  # (the robot really drove and reached with both hands full)
    for held, poses in in_hand.items():  # rigid in its hand, the second grasp included
        drift = max(np.linalg.norm(p[:3, 3] - poses[0][:3, 3]) for p in poses)
        assert drift < 1e-3, f"{held} moved {drift * 1000:.1f} mm in its hand"


@pytest.mark.slow
def test_bench_carries_one_and_two_and_says_what_two_hands_save(tmp_path: Path) -> None:
    out = tmp_path / "results"
    args = ("bench", "--setups", "v1,c1", "--strategies", "opm-batch", "--carry", "1,2",
            "--trials", "1", "--backend", "kinematic", "--workers", "1", "--no-plots",
            "--out", str(out))
    result = run_cli(*args)
    assert result.returncode == 0, result.stderr
    rows = list(csv.DictReader((out / "trials.csv").open()))
    assert sorted((r["setup"], r["carry"]) for r in rows) == [
        ("c1", "1"), ("c1", "2"), ("v1", "1"), ("v1", "2")]
    assert all(r["success"] == "True" for r in rows)
    stored = {s.name for s in load_setup("c1").items if s.container}
    for row in rows:
        trips = json.loads(row["trips"])
        if row["carry"] == "1":
            assert all(len(t) == 1 for t in trips)
        else:
            assert any(len(t) == 2 for t in trips)
            # an item in a drawer or the cupboard needs a free hand: it travels alone
            if row["setup"] == "c1":
                assert all(len(t) == 1 for t in trips if set(t) & stored), trips
    summary = (out / "summary.md").read_text()
    assert "Two hands against one" in summary and "all setups" in summary
    page = run_cli("report", str(out), "--no-plots")
    assert page.returncode == 0, page.stderr
    html = (out / "report.html").read_text()
    assert 'id="two-hands"' in html and "--carry 2" in html
    again = run_cli(*args)  # (carry is part of the key: nothing left to run)
    assert again.returncode == 0 and "(4 already in" in again.stderr, again.stderr
    assert len(list(csv.DictReader((out / "trials.csv").open()))) == 4


def test_optimal_batch_with_one_hand_is_optimal_not_the_opm() -> None:
    """(A red-team user compared `optimal-batch` at --carry 1 against the OPM on v3 and got
    the OPM's own order: one item a trip was the OPM's greedy choice.)"""
    with TrialRunner("v3", backend="kinematic") as runner:
        orders = {name: runner.run(name, seed=0).order
                  for name in ("opm", "optimal", "optimal-batch")}
    assert orders["optimal-batch"] == orders["optimal"] != orders["opm"], orders


def test_optimal_batch_names_itself_when_a_task_is_too_large() -> None:
    from cramlite.strategies import StrategyError

    many = [Candidate(f"i{n}", (float(n), 0.0, 0.0), then_at=(float(n), 1.0, 0.0))
            for n in range(16)]
    with pytest.raises(StrategyError, match="optimal-batch plans exactly for at most 15"):
        make_strategy("optimal-batch").choose(many, ROBOT)
