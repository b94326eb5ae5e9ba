"""Recovery in a transport: an item one hand can take but not put down is put back and
carried by the other hand (kinematic backend: this is about the plan, on every Python)."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import pytest

from cramlite.designators import (
    MoveTorsoAction,
    ParkArmsAction,
    PlaceAction,
    PlacementFailed,
    TransportAction,
    simulated_robot,
)
from cramlite.trace import read_trace
from cramlite.trace.check import checker_for, penetrations
from cramlite.trace.physics import physics_findings
from cramlite.trial import TrialRunner
from cramlite.world import load_setup


@pytest.mark.parametrize("setup, strategy, seed, item", [("c1", "opm", 1, "bowl")])
def test_clearing_up_the_other_hand_puts_it_into_the_cupboard(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, setup: str, strategy: str, seed: int,
        item: str) -> None:
    """Clearing up: the right hand takes the item from the island but cannot put it down
    in the cupboard (here refused, injected: the planner now finds its own way in nearly
    always; before, it missed it in 8 of 10 trials of c3). The item is put back where it
    was, as it was picked up in reverse (in c1 a new arm solution for that spot once
    touched the island, and the cup was let go in the air), and the left hand carries it
    in. Every executed state of the put-back and the second fetch is checked. (Since the
    IK's closed form, the right hand no longer takes c1's cup first; its bowl it does.)"""
    _refuse_deliveries(monkeypatch, lambda name, arm: name == item and arm == "right")
    path = tmp_path / f"{setup}.jsonl"
    with TrialRunner(setup, backend="kinematic") as runner:
        result = runner.run(strategy, plan="clear-table", seed=seed, trace=path)
        origin = load_setup(setup).item(item).target.xyz  # (where clearing up takes it)
    assert result.success, result.failures
    log = "\n".join(result.log)
    assert f"could not put {item} down with the right arm" in log, log
    assert f"put {item} back at ({origin[0]:.2f}, {origin[1]:.2f})" in log, log
    assert "let go" not in log, log
    assert f"taking {item} with the left arm" in log, log
    placed = [line for line in result.log if line.startswith(f"placed {item}")]
    assert " left arm " in placed[-1], placed
    assert result.items[item]["ok"], result.items[item]
    # every executed state, the put-back and the second fetch included: nothing inside
    # anything (the robot itself too), nothing tipped, magnetised or jerked
    trace = read_trace(path)
    found = penetrations(trace, substeps=1)
    assert found == [], [f.describe() for f in found]
    physics = physics_findings(trace, checker_for(trace))
    assert physics == [], [f.describe() for f in physics]


def _refuse_deliveries(monkeypatch: pytest.MonkeyPatch,
                       refuse: Callable[[str, str], bool]) -> None:
    """A delivery to a target is refused (injected), as a taken place would be, where
    `refuse(item, arm holding it)` says so. Putting it back (on its surface) is left as it
    is."""
    deliver = TransportAction._deliver

    def refusing(self, ctx, obj, planned=None, target=None):
        if self.target is not None and \
                refuse(obj.name, next(a for a, h in ctx.holding.items() if h.obj == obj.name)):
            raise PlacementFailed("the place is taken (injected)", obj=obj.name)
        return deliver(self, ctx, obj, planned, target)

    monkeypatch.setattr(TransportAction, "_deliver", refusing)


@pytest.fixture
def refused(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Every delivery to a target is refused; the arm that held the item each time is
    recorded."""
    arms: list[str] = []

    def record(item: str, arm: str) -> bool:
        arms.append(arm)
        return True

    _refuse_deliveries(monkeypatch, record)
    return arms


@pytest.mark.parametrize("origin_taken", [False, True])
def test_when_neither_hand_can_put_it_down_the_failure_says_so_and_the_hands_are_empty(
        refused: list[str], monkeypatch: pytest.MonkeyPatch, origin_taken: bool) -> None:
    """A delivery to the target that always fails (a refused placement, injected): the
    item is put back, the other hand tries, and the failure that escapes names both. It
    is put back where it was; if that spot is taken (injected too), beside it on the
    same surface, never let go in the air."""
    setup = load_setup("v1")
    origin = setup.item("milk").pose.xyz
    if origin_taken:
        place = PlaceAction.execute

        def taken(self, ctx):
            if math.dist(self.target, origin) < 1e-9:
                raise PlacementFailed("the spot is taken (injected)", obj="milk")
            return place(self, ctx)

        monkeypatch.setattr(PlaceAction, "execute", taken)
    with simulated_robot(setup, backend="kinematic") as ctx:
        ParkArmsAction().perform(ctx)
        MoveTorsoAction(0.25).perform(ctx)
        with pytest.raises(PlacementFailed) as caught:
            TransportAction("milk", target=setup.item("milk").target.xyz).perform(ctx)
        assert sorted(refused) == ["left", "right"]  # each hand tried once
        failure = caught.value
        first = refused[0]
        second = "left" if first == "right" else "right"
        assert failure.tried[0] == f"{first} arm: placement failed: the place is taken " \
                                   "(injected)", failure.tried
        assert f"{second} arm: placement failed: the place is taken (injected)" in \
            failure.tried, failure.tried
        assert not ctx.holding and not ctx.scene.held
        (x, y, z), _ = ctx.scene.object_pose("milk")
        assert abs(z - origin[2]) < 0.002  # standing on the counter
        off = math.dist((x, y), origin[:2])
        assert (0.01 < off < 0.3) if origin_taken else off < 0.002, off
        assert ctx.scene.surface_under(x, y, z, 0.002).name == "counter"
        assert sum("put milk back" in line for line in ctx.log) == 2, ctx.log
        assert not any("let go" in line for line in ctx.log), ctx.log


def test_the_arms_a_transport_is_given_are_the_only_ones_it_uses(refused: list[str]) -> None:
    setup = load_setup("v1")
    with simulated_robot(setup, backend="kinematic") as ctx:
        ParkArmsAction().perform(ctx)
        MoveTorsoAction(0.25).perform(ctx)
        with pytest.raises(PlacementFailed, match="the place is taken"):
            TransportAction("milk", target=setup.item("milk").target.xyz,
                            arms=["left"]).perform(ctx)
    assert refused == ["left"]


def test_an_item_that_failed_where_it_stands_is_tried_again_when_the_rest_is_done(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """c1, clearing up, opm, seed 4: the cup on the island cannot be put into the cupboard
    while the milk beside it is still there (refused, injected: as when the cereal and
    milk were in the way of the left hand, before the IK's closed form). Tried again when
    the rest is done, it is taken and put in."""
    from cramlite.designators import TransportAction

    deliver = TransportAction._deliver
    milk = load_setup("c1").item("milk").target.xyz  # (where clearing up finds it)

    def refusing(self, ctx, obj, planned=None, target=None):
        (x, y, _), _ = ctx.scene.object_pose("milk")
        if obj.name == "cup" and math.dist((x, y), milk[:2]) < 0.05:
            raise PlacementFailed("the place is taken (injected)", obj=obj.name)
        return deliver(self, ctx, obj, planned, target)

    monkeypatch.setattr(TransportAction, "_deliver", refusing)
    with TrialRunner("c1", backend="kinematic") as runner:
        result = runner.run("opm", plan="clear-table", seed=4)
    assert result.success, result.failures
    assert "trying cup again (other items moved since it failed)" in result.log, result.log
    assert "cup: done at the second try" in result.log, result.log
    assert result.order.count("cup") == 1  # the strategy's choices, once each
    assert [trip for trip in result.trips if trip == ["cup"]] == [["cup"], ["cup"]]
    placed = [line for line in result.log if line.startswith("placed cup")]
    assert len(placed) == 1, result.log


@pytest.mark.parametrize("milk_first", [False, True])
def test_an_item_out_of_reach_is_reported_once_and_tried_again_only_if_others_moved(
        milk_first: bool) -> None:
    """`unreachable`: the milk is out of reach. Fetched last (the baseline order) nothing
    moves after it fails: it is not tried again. Fetched first, the others move after:
    it is tried again, fails again, and is reported once."""
    order = ["milk", "breakfast-cereal", "cup", "bowl", "spoon"] if milk_first else None
    with TrialRunner("unreachable", backend="kinematic") as runner:
        result = runner.run("baseline", seed=0, order=order)
    assert not result.success
    assert [f["item"] for f in result.failures] == ["milk"], result.failures
    assert result.failures[0]["type"] == "ObjectUnreachable"
    assert result.order.count("milk") == 1
    log = "\n".join(result.log)
    again = "trying milk again (other items moved since it failed)" in result.log
    assert again == milk_first, log
    assert ("not trying milk again: nothing has moved since it failed" in result.log) \
        != milk_first, log
    assert ("failed again: milk" in log) == milk_first, log


@pytest.mark.parametrize("name", ["c2", "c1"])
def test_an_item_from_storage_closed_since_is_put_back_on_the_counter_not_in_the_air(
        refused: list[str], tmp_path: Path, name: str) -> None:
    """The cup is taken out of drawer_2 (c2) or the cupboard (c1) and the free hand
    closes it; the delivery is refused (injected). Where the cup stood is in the air now
    (the drawer moved) or behind a closed door: it is put on the counter, the nearest
    surface an item of the setup stands on, and the trace finds it standing there
    (before, it was set down in the air, or let go there)."""
    setup = load_setup(name)
    with simulated_robot(setup, backend="kinematic") as ctx:
        ctx.open_trace(tmp_path / "t.jsonl", name, "transport", "none", 0, "kinematic")
        ParkArmsAction().perform(ctx)
        MoveTorsoAction(0.25).perform(ctx)
        with pytest.raises(PlacementFailed):
            TransportAction("cup", target=setup.item("cup").target.xyz).perform(ctx)
        ctx.flush_deferred()  # (the arm parked on the way to a drive that never came)
        ctx.trace.close()
        assert len(refused) == 2 and not ctx.holding
        assert all(abs(v) < 1e-6 for v in ctx.scene.belief.world_joints.values())  # closed
        point, _ = ctx.scene.object_pose("cup")
        assert ctx.scene.surface_under(*point, 0.002).name == "counter", point
        assert not any("let go" in line for line in ctx.log), ctx.log
    trace = read_trace(tmp_path / "t.jsonl")
    assert [f.describe() for f in physics_findings(trace, checker_for(trace))] == []


def test_an_item_of_a_trip_carrying_two_is_tried_again_when_the_other_was_in_its_way(
        ) -> None:
    """c2, clearing up, two hands, opm, seed 3: the cereal and the milk share a trip; the
    cereal, put down first, is in the way of the milk's spot. Nothing moves after that,
    but the cereal moved during the trip: the milk is tried again alone, and goes."""
    with TrialRunner("c2", backend="kinematic") as runner:
        result = runner.run("opm", plan="clear-table", seed=3, carry=2)
    assert result.success, result.failures
    assert "trying milk again (other items moved since it failed)" in result.log
    assert result.order.count("milk") == 1
    assert result.trips[-2:] == [["breakfast-cereal", "milk"], ["milk"]], result.trips


def test_failures_are_reported_in_fetch_order(monkeypatch) -> None:
    """An item that fails where it stands is tried again at the end, yet its failure
    keeps its place in fetch order: the milk (fetched first, tried again, failing again)
    is reported before the cup (fetched second, not tried again). The two failures are
    made here: what is tested is the plan's bookkeeping."""
    import importlib

    set_table = importlib.import_module("cramlite.plans.set_table")
    from cramlite.designators import ObjectUnreachable

    tries = {"milk": 0, "cup": 0}

    class Failing(TransportAction):
        def execute(self, ctx):
            name = self.object.names[0]
            if name in tries:
                tries[name] += 1
                raise ObjectUnreachable(f"made to fail here, try {tries[name]}", obj=name)
            return super().execute(ctx)

    monkeypatch.setattr(set_table, "TransportAction", Failing)
    monkeypatch.setattr(set_table, "can_try_again", lambda ctx, name: name == "milk")
    order = ["milk", "cup", "breakfast-cereal", "bowl", "spoon"]
    with TrialRunner("v1", backend="kinematic") as runner:
        result = runner.run("baseline", seed=0, order=order)
    assert "trying milk again (other items moved since it failed)" in result.log
    assert [f["item"] for f in result.failures] == ["milk", "cup"], result.failures
    assert tries == {"milk": 2, "cup": 1}
    # (the milk's second failure stands in for its first)
    assert [f["message"].endswith("try 2") for f in result.failures] == [True, False]
