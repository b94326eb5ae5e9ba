"""Seeded failure injection: an injected grasp failure is recovered by the pick-up's next
candidate and counted, a refused drive by the navigation's next base pose; the same seed
gives the same failures; a bench keys its trials by the injection and counts what it did."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from cramlite.designators.injection import inject_text, parse_inject
from cramlite.errors import UserInputError
from cramlite.trial import TrialRunner
from tests.conftest import run_cli


def _walk(nodes):
    for node in nodes:
        yield node
        yield from _walk(node["children"])


def test_an_injected_grasp_failure_is_recovered_by_the_next_candidate_and_counted() -> None:
    with TrialRunner("v1", backend="kinematic") as runner:
        result = runner.run("opm", seed=2, inject={"grasp": 0.3, "navigate": 0.2})
        again = runner.run("opm", seed=2, inject={"grasp": 0.3, "navigate": 0.2})
        clean = runner.run("opm", seed=2)
    assert result.success and result.order == clean.order, result.failures
    assert result.injected["grasp"] >= 1 and result.injected["navigate"] >= 1
    picks = [n for n in _walk(result.actions) if n["name"] == "PickUpAction"]
    slipped = [n for n in picks if n["status"] == "failed"
               and "injected" in (n["failure"] or {}).get("message", "")]
    assert len(slipped) == result.injected["grasp"]
    for node in slipped:  # the gripper opened, the arm backed off; then picked up again
        after = [c["name"] for c in node["children"]][-3:]
        assert after == ["AttachMotion", "MoveGripperMotion", "MoveArmJointsMotion"], after
        assert any(p["object"] == node["object"] and p["status"] == "succeeded"
                   and p["start_s"] > node["end_s"] for p in picks)
    drives = [n for n in _walk(result.actions) if n["name"] == "NavigateAction"
              and n["status"] == "failed" and "injected" in n["failure"]["message"]]
    assert len(drives) == result.injected["navigate"]
    # the same seed, the same failures; planning's own random choices did not shift
    assert again.injected == result.injected and again.robot_time_s == result.robot_time_s
    assert clean.injected == {} and result.robot_time_s > clean.robot_time_s


def test_the_injection_spec_is_checked_and_spelled_one_way() -> None:
    assert parse_inject("navigate=0.05, grasp=0.1") == {"navigate": 0.05, "grasp": 0.1}
    assert inject_text(parse_inject("navigate=0.05,grasp=0.1")) == "grasp=0.1,navigate=0.05"
    for bad, words in (("grasp", "KIND=PROBABILITY"), ("grasp=1.5", "[0, 1]"),
                       ("grasp=x", "[0, 1]"), ("slip=0.1", "grasp, navigate, detect"),
                       ("grasp=0.1,grasp=0.2", "twice")):
        with pytest.raises(UserInputError, match=words.replace("[", r"\[")):
            parse_inject(bad)
    done = run_cli("run", "v1", "--inject", "grasp=2")
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "--inject" in done.stderr


def test_bench_keys_trials_by_the_injection_and_counts_recoveries(tmp_path: Path) -> None:
    out = tmp_path / "results"
    common = ("bench", "--setups", "v1", "--strategies", "opm", "--trials", "2", "--backend",
              "kinematic", "--workers", "1", "--no-plots", "--out", str(out))
    done = run_cli(*common, "--inject", "navigate=0.2,grasp=0.3")
    assert done.returncode == 0, done.stderr
    rows = list(csv.DictReader((out / "trials.csv").open()))
    assert [r["inject"] for r in rows] == ["grasp=0.3,navigate=0.2"] * 2
    drawn = [json.loads(r["injected"]) for r in rows]
    assert all(r["success"] == "True" for r in rows) and any(drawn)
    summary = (out / "summary.md").read_text()
    assert "Injected failures (--inject):" in summary and "items lost" in summary
    assert 'id="injected"' in (out / "report.html").read_text()
    # another injection is another trial: nothing of the first counts as done
    other = run_cli(*common, "--inject", "grasp=0.1")
    assert other.returncode == 0, other.stderr
    rows = list(csv.DictReader((out / "trials.csv").open()))
    assert sorted(r["inject"] for r in rows) == ["grasp=0.1"] * 2 + ["grasp=0.3,navigate=0.2"] * 2
