"""Issue 13: the 2-step model, the reference protocol, random expectations, grid fits."""

from __future__ import annotations

import itertools
import statistics

import numpy as np
import pytest

from cramlite.evaluation.data import Episode, load_episodes
from cramlite.evaluation.evaluate import evaluate
from cramlite.evaluation.fit import fit, source_grid
from cramlite.evaluation.metrics import (
    edit_distance,
    expected_ape,
    generate_sequence,
    random_ape,
    random_order_edit,
)
from cramlite.evaluation.protocol import ape_steps, pool
from cramlite.resources import shipped_data_path
from cramlite.strategies import Candidate, make_strategy

DATA = shipped_data_path("table-setting")
ORIGIN = (0.0, 0.0, 0.0)


def episode(names: str, positions: dict[str, tuple], starts: list[tuple],
            cells: dict[str, str] | None = None, contained: tuple[str, ...] = ()) -> Episode:
    seq = tuple(names.split(","))
    items = tuple(Candidate(n, positions[n], contained=n in contained) for n in seq)
    return Episode(id="t", activity="test", sequence=seq, items=items,
                   taken=tuple(range(len(seq))), start_positions=tuple(starts),
                   cells=cells or {})


@pytest.fixture(scope="module")
def shipped() -> list[Episode]:
    return load_episodes(DATA)[0]


# a (1,0) is nearest the origin; from a, b (3,0) is nearer than c (-1.5,0); from the
# origin c is nearer than b. The subject stands at the origin before every step.
SPLIT = {"a": (1.0, 0.0, 0.0), "b": (3.0, 0.0, 0.0), "c": (-1.5, 0.0, 0.0)}


def test_two_step_differs_from_one_step_where_the_second_choice_differs() -> None:
    ep = episode("a,b,c", SPLIT, [ORIGIN] * 3)
    one, two = make_strategy("opm"), make_strategy("opm-2step")
    assert generate_sequence(one, ep) == ["a", "c", "b"]
    assert generate_sequence(two, ep) == ["a", "b", "c"]
    assert expected_ape(one, ep) == 1 and expected_ape(two, ep) == 0
    # the second choice is the same from a and from the origin: the models agree
    same = episode("a,c,b", {**SPLIT, "b": (9.0, 0.0, 0.0)}, [ORIGIN] * 3)
    assert generate_sequence(one, same) == generate_sequence(two, same) == ["a", "c", "b"]
    assert expected_ape(one, same) == expected_ape(two, same) == 0


def test_two_step_is_not_the_one_step_model_on_the_shipped_data(shipped) -> None:
    one = evaluate(shipped, "opm", {"c": 1.4}, metric="edit").scores
    two = evaluate(shipped, "opm-2step", {"c": 1.4}, metric="edit").scores
    differ = sum(a != b for a, b in zip(one, two, strict=True))
    print("episodes that differ", differ, np.mean(one), np.mean(two))
    assert 80 <= differ <= 120  # the issue measured 97 of 186 with the reference code


def test_reference_candidates_are_distinct_names_at_their_last_coordinate() -> None:
    ep = Episode(id="t", activity="test", sequence=("fork", "plate", "fork"),
                 items=(Candidate("fork", (1.0, 0.0, 0.0)), Candidate("plate", (2.0, 0.0, 0.0)),
                        Candidate("fork", (5.0, 0.0, 0.0))),
                 taken=(0, 1, 2), start_positions=(ORIGIN,) * 3,
                 cells={"containment": "plate2,cup"})
    ref = pool(ep, "reference")
    assert [(c.name, c.position[0], c.contained) for c in ref] == \
        [("fork", 5.0, False), ("plate", 2.0, True)]  # substring: "plate" in "plate2,cup"
    assert [c.contained for c in pool(ep, "heldout")] == [False, False, False]
    # APE steps: a repeated name stays offered until its last occurrence
    assert [[c.name for c in s.candidates] for s in ape_steps(ep, "reference")] == \
        [["fork", "plate"], ["fork", "plate"]]
    assert [[c.name for c in s.candidates] for s in ape_steps(ep, "heldout")] == \
        [["fork", "fork", "plate"], ["fork", "plate"]]
    # generation covers the distinct names only; edit is unrestricted over the longer
    assert generate_sequence(make_strategy("opm"), ep, "reference") == ["plate", "fork"]
    assert evaluate([ep], "opm", metric="edit", protocol="reference").scores == \
        [pytest.approx(edit_distance(["plate", "fork"], ep.sequence, restricted=False))]
    assert edit_distance(["plate", "fork"], ep.sequence, restricted=False) == \
        pytest.approx(1 / 3)  # insert "fork" in front, over the longer length 3


def test_reference_protocol_reproduces_the_published_code(shipped) -> None:
    edit = evaluate(shipped, "opm", {"c": 1.4}, metric="edit", protocol="reference")
    ape = evaluate(shipped, "opm", {"c": 1.7}, metric="ape", protocol="reference")
    print("reference edit", edit.as_dict()["mean"], "ape", ape.as_dict()["mean"])
    assert 0.600 <= edit.as_dict()["mean"] <= 0.610  # issue: 0.605-0.607
    assert 4.03 <= ape.as_dict()["mean"] <= 4.17  # issue: 4.10-4.16 (seed-dependent)
    own = evaluate(shipped, "opm", {"c": 1.4}, metric="edit").as_dict()["mean"]
    assert own == pytest.approx(0.6176, abs=5e-4)  # cramlite's own convention differs


def test_random_is_scored_by_its_expectation() -> None:
    positions = {n: (float(i), 0.0, 0.0) for i, n in enumerate("abcd")}
    ep = episode("a,b,a,c,d", {**positions}, [ORIGIN] * 5)
    value, exact = random_order_edit(ep, restricted=True)
    names = list(ep.sequence)
    brute = statistics.mean(edit_distance(p, names) for p in itertools.permutations(names))
    assert exact and value == pytest.approx(brute)
    result = evaluate([ep], "random", metric="edit").as_dict()
    assert result["score_kind"] == "expectation"
    assert result["per_episode"][0]["score"] == pytest.approx(brute)
    assert result["per_episode"][0]["score_exact"] is True
    assert "error column" in result["random_baseline"]["definition"]
    ape = evaluate([ep], "random", metric="ape").as_dict()
    assert ape["mean"] == pytest.approx(random_ape(ep))
    assert random_ape(ep) == pytest.approx(1 - 2 / 5 + 1 - 1 / 4 + 1 - 1 / 3 + 1 - 1 / 2)
    opm = evaluate([ep], "opm", metric="ape").as_dict()
    assert opm["score_kind"] == "sampled"


def test_random_expectation_beyond_enumeration_is_a_fixed_estimate(shipped) -> None:
    longest = max(shipped, key=len)
    value, exact = random_order_edit(longest)
    assert not exact and value == random_order_edit(longest)[0]  # same estimate every time
    assert 0.5 < value < 1.0


@pytest.mark.parametrize("strategy", ["opm-2step", "optimal", "opm"])
@pytest.mark.parametrize("protocol", ["heldout", "reference"])
def test_vectorised_fit_equals_point_by_point_evaluation(shipped, strategy, protocol) -> None:
    episodes = shipped[::9]
    grid = source_grid()[[0, 17, 555, 1099]]
    for metric in ("ape", "expected-ape"):
        result = fit(episodes, strategy, dims=["xy"], metric=metric, repeats=20, seed=4,
                     configs=grid, protocol=protocol)
        for g, row in enumerate(grid):
            params = dict(zip(["strong_k", "mid_k", "food_k", "c"], row, strict=True))
            direct = evaluate(episodes, strategy, params, "xy", metric=metric, repeats=20,
                              seed=4, protocol=protocol).scores
            assert np.allclose(result.scores["xy"][:, g], direct), (metric, row)


def test_point_by_point_fit_uses_worker_processes_with_the_same_result(shipped) -> None:
    episodes = shipped[:12]
    grid = source_grid()[[0, 300, 700, 1099]]
    one = fit(episodes, "opm-2step", ["xy"], "edit", repeats=5, configs=grid, workers=1)
    two = fit(episodes, "opm-2step", ["xy"], "edit", repeats=5, configs=grid, workers=2)
    assert np.array_equal(one.scores["xy"], two.scores["xy"])
