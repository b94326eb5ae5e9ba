"""`cramlite simulate` and parameter recovery: synthetic episodes are seeded, load as
recorded ones do, follow the generating parameters, and `fit` recovers them."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from cramlite.evaluation.data import Episode, load_episodes, parse_row
from cramlite.evaluation.fit import PARAM_NAMES, FitResult, fit
from cramlite.evaluation.simulate import episode_row, simulate, softmax_choice
from cramlite.resources import resolve_data_path
from cramlite.strategies import Candidate
from tests.conftest import run_cli

GENERATING = {"strong_k": 0.6, "mid_k": 0.7, "food_k": 1.2, "c": 1.4}


def table_setting():
    return load_episodes(resolve_data_path("table-setting"))[0]


def test_simulated_episodes_are_seeded_and_read_back_as_drawn() -> None:
    like = table_setting()
    one = simulate(like, 40, params=GENERATING, seed=3)
    again = simulate(like, 40, params=GENERATING, seed=3)
    other = simulate(like, 40, params=GENERATING, seed=4)
    names = [[c.name for c in e.order] for e in one]
    assert names == [[c.name for c in e.order] for e in again]
    assert names != [[c.name for c in e.order] for e in other]
    assert simulate(like, 5, params=GENERATING, seed=3)[4].order == one[4].order
    for drawn in one:
        episode = parse_row(episode_row(drawn))
        source = drawn.source
        assert episode.activity == source.activity
        assert episode.start_positions == source.start_positions
        # the same task: the same items (with positions, categories and storage) ...
        assert sorted(episode.sequence_items(), key=repr) == \
            sorted(source.sequence_items(), key=repr)
        # ... taken in the drawn order, a repeated name's instances included
        assert [c.position for c in episode.sequence_items()] == \
            [c.position for c in drawn.order]


def test_the_softmax_prefers_low_costs_by_the_temperature() -> None:
    rng = np.random.default_rng(0)
    costs = [1.0, 1.05, 2.0]
    draws = np.bincount([softmax_choice(costs, 0.05, rng) for _ in range(4000)], minlength=3)
    # exp(-0.05 / 0.05) = 1/e: the second is taken e times less often; the third never
    assert abs(draws[0] / draws[1] - np.e) < 0.35 and draws[2] == 0
    assert {softmax_choice(costs, 0.0, rng) for _ in range(50)} == {0}
    hot = np.bincount([softmax_choice(costs, 100.0, rng) for _ in range(3000)], minlength=3)
    assert hot.min() > 850


def test_fit_recovers_the_generating_parameters() -> None:
    drawn = simulate(table_setting(), 186, params=GENERATING, temperature=0.05, seed=0)
    episodes = [parse_row(episode_row(e)) for e in drawn]
    configs = np.array([(s, round(s + 0.1, 1), 1.2, c) for s in (0.2, 0.4, 0.6, 0.8)
                        for c in (1.0, 1.4, 1.8)])
    result = fit(episodes, "opm", ("xy",), "expected-ape", configs=configs)
    _, index = result.best("xy")
    recovered = result.params(index)
    assert recovered["strong_k"] == 0.6 and recovered["c"] == 1.4, recovered


def test_a_plateau_reports_its_span_and_its_middle_as_best() -> None:
    configs = np.array([(0.2, 0.3, food, 1.7) for food in (1.1, 1.2, 1.3, 1.4, 1.5)])
    scores = np.array([[3.0, 2.0, 2.0, 2.0, 4.0], [3.0, 1.0, 1.0, 1.0, 1.0]])
    result = FitResult("opm", "expected-ape", ["xy"], configs, {"xy": scores})
    assert result.tied_best("xy")["food_k"] == (1.2, 1.4)
    assert result.tied_best("xy")["c"] == (1.7, 1.7)
    assert result.params(result.best("xy")[1])["food_k"] == 1.3
    assert set(PARAM_NAMES) == set(result.tied_best("xy"))


def test_simulate_on_the_command_line_writes_a_file_fit_reads(tmp_path) -> None:
    out = tmp_path / "sim.csv"
    made = run_cli("simulate", "--params", "strong_k=0.4,mid_k=0.5,c=1.3", "--episodes",
                   "30", "--seed", "1", "--out", str(out))
    assert made.returncode == 0, made.stderr
    assert "wrote 30 episodes" in made.stdout and out.exists()
    fitted = run_cli("fit", str(out), "--dims", "xy", "--metric", "expected-ape", "--out",
                     str(tmp_path / "fit"))
    assert fitted.returncode == 0, fitted.stderr
    assert "opm fit on 30 episodes" in fitted.stdout


def test_simulate_refuses_bad_input_in_one_line(tmp_path) -> None:
    cases = [(["--temperature", "-1"], "--temperature: expected a temperature from 0 to 1e6"),
             (["--strategy", "random"], "--strategy: expected a strategy with a cost"),
             (["--params", "c=x"], "--params: expected a number for c"),
             (["--like", str(tmp_path / "missing.csv")], "missing.csv")]
    for extra, expected in cases:
        result = run_cli("simulate", "--out", str(tmp_path / "s.csv"), *extra)
        lines = result.stderr.strip().splitlines()
        assert result.returncode == 2 and len(lines) == 1, result.stderr
        assert expected in lines[0], lines[0]


def test_the_likelihood_of_a_hand_made_step_is_the_softmax_of_its_costs() -> None:
    # from the origin, the cup 1 m away, the bowl 2 m (k = c = 1: the costs are the
    # distances); the subject takes the bowl first, then the cup (a step that offers
    # one item is not scored)
    from cramlite.evaluation.evaluate import baseline_score
    from cramlite.evaluation.fit import grid_nll

    seq = ("bowl", "cup")
    items = (Candidate("bowl", (2.0, 0.0, 0.0)), Candidate("cup", (1.0, 0.0, 0.0)))
    episode = Episode(id="t", activity="test", sequence=seq, items=items, taken=(0, 1),
                      start_positions=((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)), cells={})
    configs = np.array([(1.0, 1.0, 1.0, 1.0)])
    for temperature in (0.5, 1.0, 2.0):
        nll = grid_nll(episode, configs, "xy", "power", temperature=temperature)
        # P(bowl) = exp(-2/T) / (exp(-1/T) + exp(-2/T))
        expected = -math.log(math.exp(-2 / temperature)
                             / (math.exp(-1 / temperature) + math.exp(-2 / temperature)))
        assert nll[:, 0] == pytest.approx([expected])
    # a choice far costlier than the best is unlikely, not impossible: its cost over T
    assert grid_nll(episode, configs, "xy", "power", temperature=1e-6)[0, 0] == \
        pytest.approx(1e6)
    # uniform guessing: log 2
    assert baseline_score(episode, "likelihood")[0] == pytest.approx(math.log(2))
    for cold in (0.0, 5e-324):
        with pytest.raises(ValueError, match="temperature >= 1e-06"):
            grid_nll(episode, configs, "xy", "power", temperature=cold)


def test_the_likelihood_fit_recovers_what_the_apes_plateau_cannot_tell_apart() -> None:
    """Food k changes few of the model's choices on the table-setting tasks: the expected
    APE fits a plateau of food k values equally well; the likelihood of the choices (how
    much likelier each was than the others) picks the generating value."""
    truth = {"strong_k": 0.4, "mid_k": 0.5, "food_k": 1.5, "c": 1.3}
    drawn = simulate(table_setting(), 744, params=truth, temperature=0.2, seed=0)
    episodes = [parse_row(episode_row(e)) for e in drawn]
    configs = np.array([(0.4, 0.5, food, c) for food in (1.1, 1.3, 1.5, 1.7, 1.9)
                        for c in (1.1, 1.3, 1.5)])
    by_ape = fit(episodes, "opm", ("xy",), "expected-ape", configs=configs)
    by_likelihood = fit(episodes, "opm", ("xy",), "likelihood", configs=configs,
                        temperature=0.2)
    lo, hi = by_ape.tied_best("xy")["food_k"]
    assert hi - lo >= 0.4 - 1e-9  # (the APE cannot tell them apart)
    best = by_likelihood.params(by_likelihood.best("xy")[1])
    assert best["food_k"] == 1.5 and best["c"] == 1.3, best
    assert by_likelihood.tied_best("xy")["food_k"] == (1.5, 1.5)


def test_fit_likelihood_from_the_command_line(tmp_path: Path) -> None:
    sim = tmp_path / "sim.csv"
    assert run_cli("simulate", "--params", "strong_k=0.4,mid_k=0.5,food_k=1.5,c=1.3",
                   "--episodes", "40", "--temperature", "0.2", "--out", str(sim)).returncode == 0
    done = run_cli("fit", str(sim), "--metric", "likelihood", "--temperature", "0.2",
                   "--dims", "xy", "--out", str(tmp_path / "fit"), "--json")
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary["metric"] == "likelihood" and summary["random_baseline_mean"] > 0
    for args, message in (
            (["--temperature", "0"], "--temperature: expected a temperature from 1e-6 to 1e6"),
            (["--temperature", "5e-324"], "--temperature: expected a temperature from 1e-6 to 1e6"),
            (["--metric", "ape", "--temperature", "0.2"],
             "--temperature: applies to --metric likelihood only"),
            (["--strategy", "random"], "likelihood metric needs a strategy with a cost")):
        if "--metric" not in args:
            args = ["--metric", "likelihood", *args]
        bad = run_cli("fit", str(sim), *args, "--out", str(tmp_path / "bad"))
        assert bad.returncode == 2 and message in bad.stderr and "Traceback" not in bad.stderr
