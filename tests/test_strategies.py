"""Strategies against hand-computed cases."""

from __future__ import annotations

import itertools
import math
from collections import Counter

import numpy as np
import pytest

from cramlite.strategies import (
    Candidate,
    CostModel,
    OPMParams,
    StrategyError,
    make_strategy,
    span_weights,
)


def cand(name: str, x: float, y: float, z: float = 0.0, **kw) -> Candidate:
    return Candidate(name, (x, y, z), **kw)


def run_order(strategy, items, agent, then_at=None) -> list[str]:
    remaining, order = list(items), []
    strategy.reset(items, agent)
    while remaining:
        chosen = strategy.choose(remaining, agent)
        order.append(chosen.name)
        remaining.remove(chosen)
        agent = then_at if then_at is not None else chosen.after_position()
    return order


def test_opm_cost_is_eq_3_1_by_hand() -> None:
    s = make_strategy("opm")
    items = [cand("plate", 3.0, 4.0, category="mid"), cand("cup", 2.0, 0.0, contained=True),
             cand("tray", 0.0, 6.0, category="strong"), cand("pot", 1.0, 1.0, category="food")]
    costs = s.costs(items, (0.0, 0.0, 0.0))
    expected = [5.0**0.3, 2.0 * 1.7, 6.0**0.2, math.sqrt(2) ** 1.2]
    print(costs, expected)
    assert costs == pytest.approx(expected)
    assert s.choose(items, (0, 0, 0)).name == "tray"  # 6^0.2 = 1.43 is the lowest


def test_d_below_one_quirk_is_kept() -> None:
    # For d < 1 and k < 1, d**k > d: the strong-k item 0.5 m away costs MORE than a
    # default item 0.6 m away (0.5**0.2 = 0.87 > 0.6). Eq. 3.1 is kept exact.
    s = make_strategy("opm")
    items = [cand("tray", 0.5, 0.0, category="strong"), cand("fork", 0.6, 0.0)]
    assert s.costs(items, (0, 0, 0)) == pytest.approx([0.5**0.2, 0.6])
    assert s.choose(items, (0, 0, 0)).name == "fork"
    far = [cand("tray", 2.5, 0.0, category="strong"), cand("fork", 2.0, 0.0)]
    assert s.choose(far, (0, 0, 0)).name == "tray"  # beyond 1 m a low k pulls forward


@pytest.mark.parametrize(("dims", "expected"), [
    ("x", 1.0), ("y", 2.0), ("z", 3.0), ("xy", math.sqrt(5)), ("xz", math.sqrt(10)),
    ("yz", math.sqrt(13)), ("xyz", math.sqrt(14))])
def test_each_projection(dims: str, expected: float) -> None:
    model = CostModel(dims=dims)
    assert model.distance((0, 0, 0), (1, 2, 3)) == pytest.approx(expected)
    assert model.costs((0, 0, 0), np.array([[1.0, 2.0, 3.0]]), 1.0, 1.0)[0] == \
        pytest.approx(expected)


@pytest.mark.parametrize(("form", "expected"), [
    ("power", 4.0**0.5 * 1.5), ("additive", 4.0 - 0.5 + 1.5), ("product", 4.0 * 0.5 * 1.5)])
def test_each_functional_form(form: str, expected: float) -> None:
    model = CostModel(form=form)
    assert model.cost((0, 0, 0), (0, 4, 0), 0.5, 1.5) == pytest.approx(expected)
    assert model.costs((0, 0, 0), np.array([[0.0, 4.0, 0.0]]), np.array([0.5]),
                       np.array([1.5]))[0] == pytest.approx(expected)


def test_axis_weights_eq_3_5_and_3_6() -> None:
    # the thesis's example: spans x = 3, y = 2, z = 1 -> w = 1/2, 1/3, 1/6
    w = span_weights([(0, 0, 0), (3, 2, 1)])
    assert w == pytest.approx((0.5, 1 / 3, 1 / 6))
    model = CostModel(dims="xyz", axis_weights=w)
    assert model.distance((0, 0, 0), (2, 3, 6)) == pytest.approx(
        math.sqrt(4 * 0.5 + 9 / 3 + 36 / 6))
    s = make_strategy("opm", dims="xyz", axis_weights="span")
    items = [cand("a", 3.0, 0.0), cand("b", 0.0, 2.0, 1.0)]
    s.reset(items, (0, 0, 0))
    assert s.model.axis_weights == pytest.approx((0.5, 1 / 3, 1 / 6))


def test_scalar_and_vector_paths_agree() -> None:
    rng = np.random.default_rng(3)
    items = [cand(f"i{i}", *rng.uniform(-3, 3, 3), category=rng.choice(["mid", "none"]),
                  contained=bool(rng.integers(2))) for i in range(200)]
    s = make_strategy("opm")
    vector = s.costs(items, (0.1, 0.2, 0.3))
    scalar = [s.model.cost((0.1, 0.2, 0.3), c.position, *s.kc(c)) for c in items]
    assert vector == pytest.approx(scalar, rel=1e-12)


def test_ties_are_uniform_and_reproducible_by_seed() -> None:
    items = [cand("a", 1, 0), cand("b", 0, 1), cand("c", -1, 0), cand("far", 5, 5)]
    picks = Counter(make_strategy("opm", rng=seed).choose(items, (0, 0, 0)).name
                    for seed in range(3000))
    print(picks)
    assert set(picks) == {"a", "b", "c"}
    for name in "abc":
        assert abs(picks[name] / 3000 - 1 / 3) < 0.04
    first = [make_strategy("opm", rng=7).choose(items, (0, 0, 0)).name for _ in range(5)]
    assert len(set(first)) == 1
    assert [c.name for c in make_strategy("opm").tied(items, (0, 0, 0))] == ["a", "b", "c"]


def test_nearest_ignores_k_and_c() -> None:
    items = [cand("tray", 3, 0, category="strong"), cand("cup", 2, 0, contained=True)]
    assert make_strategy("opm").choose(items, (0, 0, 0)).name == "tray"
    assert make_strategy("nearest").choose(items, (0, 0, 0)).name == "cup"


def test_baseline_follows_the_given_order() -> None:
    items = [cand("a", 0, 0), cand("b", 1, 0), cand("c", 2, 0)]
    assert run_order(make_strategy("baseline"), items, (0, 0, 0)) == ["a", "b", "c"]
    s = make_strategy("baseline", order=["c", "a", "b"])
    assert run_order(s, items, (0, 0, 0)) == ["c", "a", "b"]


def test_random_is_a_seeded_permutation() -> None:
    items = [cand(n, i, 0) for i, n in enumerate("abcdef")]
    orders = [tuple(run_order(make_strategy("random", rng=s), items, (0, 0, 0)))
              for s in range(200)]
    assert all(sorted(o) == list("abcdef") for o in orders)
    assert len(set(orders)) > 150
    assert run_order(make_strategy("random", rng=5), items, (0, 0, 0)) == \
        run_order(make_strategy("random", rng=5), items, (0, 0, 0))


def test_two_step_chooses_the_second_item_from_where_the_first_is_taken() -> None:
    # From the origin "a" is nearest. Seen from a (1, 0), "b" (3, 0) is nearer than
    # "c" (-1.5, 0), so the 2-step model takes b next, although from the origin, where
    # the agent stands again, c is nearer (the 1-step model takes c).
    items = [cand("a", 1, 0), cand("b", 3, 0), cand("c", -1.5, 0)]
    origin = (0.0, 0.0, 0.0)
    assert run_order(make_strategy("opm-2step"), items, origin, then_at=origin) == \
        ["a", "b", "c"]
    assert run_order(make_strategy("opm"), items, origin, then_at=origin) == ["a", "c", "b"]
    # where the agent stands to take a (fetch_at), not a's position, decides
    far = [cand("a", 1, 0, fetch_at=(-3.0, 0.0, 0.0)), *items[1:]]
    assert run_order(make_strategy("opm-2step"), far, origin, then_at=origin) == \
        ["a", "c", "b"]
    # pairs: the third choice is again the OPM's from where the agent stands
    four = [*items, cand("d", 0.5, 0.5)]
    two = make_strategy("opm-2step")
    assert run_order(two, four, origin, then_at=origin) == ["d", "a", "c", "b"]


def test_two_step_follows_the_observed_item() -> None:
    # teacher forcing: the human took c first; the second choice is made from c
    items = [cand("a", 1, 0), cand("b", 3, 0), cand("c", -1.5, 0), cand("e", -2.5, 0)]
    two = make_strategy("opm-2step")
    two.reset(items)
    assert two.choose(items, (0, 0, 0)).name == "a"
    two.observe(items[2])
    rest = [items[0], items[1], items[3]]
    assert two.choose(rest, (0, 0, 0)).name == "e"  # nearest to c, not to the origin
    assert [c.name for c in two.taken] == ["c", "e"]


def test_optimal_matches_brute_force() -> None:
    rng = np.random.default_rng(1)
    for trial in range(5):
        items = [cand(f"i{i}", *rng.uniform(0, 4, 2), category=["mid", "none"][i % 2],
                      then_at=(float(rng.uniform(0, 4)), 0.0, 0.0)) for i in range(6)]
        s = make_strategy("optimal", rng=trial)
        best = min(itertools.permutations(items), key=lambda o: s.total_cost(o, (0, 0, 0)))
        plan = s.plan(items, (0, 0, 0))
        assert s.total_cost(plan, (0, 0, 0)) == pytest.approx(s.total_cost(best, (0, 0, 0)))
        assert run_order(make_strategy("optimal"), items, (0, 0, 0)) == [c.name for c in plan]


def test_optimal_refuses_beyond_its_limit() -> None:
    items = [cand(f"i{i}", i, 0, then_at=(i, 1.0, 0.0)) for i in range(16)]
    with pytest.raises(StrategyError, match="at most 15 items"):
        make_strategy("optimal").choose(items, (0, 0, 0))


def test_bad_names_and_params() -> None:
    with pytest.raises(StrategyError, match="unknown strategy 'greedy'.*opm"):
        make_strategy("greedy")
    with pytest.raises(StrategyError, match="unknown parameter 'strong'"):
        make_strategy("opm", params={"strong": 0.1})
    with pytest.raises(StrategyError, match="dims must be one of"):
        make_strategy("opm", dims="xyzw")
    assert OPMParams.from_mapping({"c": 1.4}).c == 1.4


def test_strategies_and_metrics_do_not_import_pybullet() -> None:
    import subprocess
    import sys
    code = ("import sys, cramlite\n"
            "from cramlite import make_strategy\n"
            "from cramlite.strategies.service import answer\n"
            "from cramlite.evaluation.fit import fit\n"
            "assert 'pybullet' not in sys.modules, sorted(m for m in sys.modules if 'bullet' in m)")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True).returncode == 0
