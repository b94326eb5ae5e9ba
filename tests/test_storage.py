"""Closed storage: drawers and a cupboard the PR2 opens and closes, stored items fetched
and put back, the OPM's c made physical, the task tree, bad setup input."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import skip_module_without_pybullet

skip_module_without_pybullet()

from cramlite.backends.pybullet.client import p
from cramlite.backends.pybullet.world import World
from cramlite.designators import MoveTorsoAction, ParkArmsAction, simulated_robot
from cramlite.designators.failures import PlanFailure
from cramlite.designators.storage import CloseAction, OpenAction
from cramlite.trace import read_trace
from cramlite.trace.replay import penetrations
from cramlite.trial import TrialRunner
from cramlite.world import load_setup
from tests.conftest import run_cli
from tests.injected import HandlesNeedBothHandsFree, NavigationFailsOnce


@pytest.fixture(scope="module")
def c2_world():
    with World.from_setup(load_setup("c2")) as world:
        yield world


def _handle_offsets(world: World, trace) -> list[float]:
    """How far the gripper's tool frame is from the handle's grasp point in every state
    where the container moves (from the trace, replayed in the world)."""
    from cramlite.backends.pybullet.replay import apply_state
    from cramlite.designators.storage import _grasp_pose

    joints, world_joints = trace.header["joints"], trace.header["world_joints"]
    out = []
    previous = None
    for state in trace.states:
        if previous is not None and state["w"] != previous["w"]:
            apply_state(world, joints, state, world_joints)
            moving = [world_joints[i] for i, (a, b) in enumerate(zip(state["w"], previous["w"],
                                                                       strict=True)) if a != b]
            container = next(c for c in world.containers.values() if c.joint == moving[0])
            grasp = _grasp_pose(world, container).translation
            out.append(min(math.dist(world.robot.link_pose(f"{arm}_gripper_tool_frame")[0],
                                     grasp) for arm in "lr"))  # the hand on the handle
        previous = state
    return out


def test_open_and_close_each_container(c2_world, tmp_path: Path) -> None:
    world = c2_world
    spoon_before = world.objects["spoon"].position()
    with simulated_robot(world, seed=0) as ctx:
        trace = tmp_path / "open-close.jsonl"
        ctx.open_trace(trace, "c2", "test", "none", 0)
        ParkArmsAction().perform(ctx)
        MoveTorsoAction(0.25).perform(ctx)
        for name, container in world.containers.items():
            OpenAction(name).perform(ctx)
            lower, upper = p.getJointInfo(world.environment, world.world_joints[container.joint],
                                          physicsClientId=world.client)[8:10]
            value = world.world_joint_positions()[container.joint]
            print(name, "open at", value, "limits", lower, upper)
            assert value == pytest.approx(container.open_value, abs=1e-6)
            assert (lower, container.open_value) == pytest.approx((0.0, upper))  # its limits
            if name == "drawer_1":  # the spoon inside rode along with the drawer
                moved = np.subtract(world.objects["spoon"].position(), spoon_before)
                assert moved == pytest.approx((-container.open_value, 0, 0), abs=1e-3)
            CloseAction(name).perform(ctx)
            assert world.world_joint_positions()[container.joint] == pytest.approx(0, abs=1e-6)
        assert world.objects["spoon"].position() == pytest.approx(spoon_before, abs=1e-3)
        ctx.trace.close()
        opened = [n for root in ctx.tasks.roots for n in root.walk()
                  if n.name in ("OpenAction", "CloseAction")]
        assert [n.status for n in opened] == ["succeeded"] * 6
        assert all(n.end_s - n.start_s > 1.0 for n in opened)  # it takes robot time
    recorded = read_trace(trace)
    assert recorded.header["world_joints"] == list(world.world_joints)  # (the URDF's order)
    offsets = _handle_offsets(world, recorded)
    print("tool to handle while it moves: max", max(offsets))
    assert len(offsets) > 50 and max(offsets) < 0.02  # the arm stays on the handle's path
    found = penetrations(recorded)
    world.set_world_joints(dict.fromkeys(world.world_joints, 0.0))
    assert found == [], [f.describe() for f in found]


def test_opening_falls_through_when_the_first_accessing_pose_fails(c2_world) -> None:
    world = c2_world
    with simulated_robot(world, seed=1) as ctx:
        ParkArmsAction().perform(ctx)
        ctx.modules = NavigationFailsOnce(world)
        OpenAction("drawer_2").perform(ctx)
        assert ctx.modules.refused == 1
        assert world.world_joint_positions()["drawer_2_joint"] == pytest.approx(0.35)
        CloseAction("drawer_2").perform(ctx)
        print(ctx.log)
        assert any("closed drawer_2" in line for line in ctx.log)


def test_a_stretch_no_base_pose_could_follow_opening_is_not_tried_closing(
        c2_world, monkeypatch) -> None:
    """The cupboard's door cannot be pulled all the way open from one base pose: it is
    opened in stages. Closing, the whole way back in one go is not searched again, and the
    door still closes, in stages."""
    from cramlite.designators import storage

    world = c2_world
    grounded = []
    ground = storage.AccessingLocation.ground

    def recording(self, ctx):
        grounded.append((round(self.start, 2), round(self.end, 2)))
        return ground(self, ctx)

    monkeypatch.setattr(storage.AccessingLocation, "ground", recording)
    with simulated_robot(world, seed=1) as ctx:
        ParkArmsAction().perform(ctx)
        OpenAction("cupboard").perform(ctx)
        assert grounded[0] == (0.0, 2.3) and len(grounded) >= 3  # one go failed: stages
        assert ("cupboard", 0.0, 2.3, frozenset({"right", "left"})) in ctx.unfollowable
        # (only the whole swing is remembered: a stage that failed from here may well
        # work from where the robot stands later, and skipping it would give up)
        assert all(key[1:3] == (0.0, 2.3) for key in ctx.unfollowable)
        grounded.clear()
        CloseAction("cupboard").perform(ctx)
        assert (2.3, 0.0) not in grounded and grounded[0] == (2.3, 1.15)
        assert world.world_joint_positions()["cupboard_door_joint"] == pytest.approx(0.0)


def test_an_unknown_container_is_a_typed_failure(c2_world) -> None:
    with simulated_robot(c2_world) as ctx, pytest.raises(PlanFailure, match="no container"):
        OpenAction("oven").perform(ctx)


@pytest.mark.parametrize("setup, strategy", [("c1", "opm"), ("c3", "opm")])
def test_stored_items_are_fetched_and_every_container_is_closed_again(
        setup: str, strategy: str, tmp_path: Path) -> None:
    trace = tmp_path / "t.jsonl"
    result = run_cli("run", setup, "--strategy", strategy, "--json", "--trace", str(trace))
    data = json.loads(result.stdout)
    print(data["order"], data["failures"])
    assert result.returncode == 0 and data["success"]
    assert data["open_close_s"] > 0
    transports = [n for n in data["actions"] if n["name"] == "TransportAction"]
    stored = {"c1": {"spoon", "bowl", "cup"}, "c3": {"milk", "bowl", "spoon"}}[setup]
    for node in transports:
        names = [c["name"] for c in node["children"]]
        print(node["object"], names)
        if node["object"] in stored:  # opened first; closed then (or by the plan's end)
            assert names.index("OpenAction") < names.index("PickUpAction")
        for child in node["children"]:
            assert child["end_s"] >= child["start_s"] >= node["start_s"]
    closes = [n for n in data["actions"] for n in [n, *n["children"]]
              if n["name"] == "CloseAction"]
    assert len(closes) >= 3
    recorded = read_trace(trace)
    assert recorded.states[-1]["w"] == [0.0, 0.0, 0.0]  # every container closed at the end
    assert max(max(s["w"]) for s in recorded.states) > 0.3  # and they were open
    # every executed state (2 cm / 0.05 rad apart) against the real meshes; `replay
    # --check` also checks halfway between them (twice the time: 17 s for a c1 trace)
    found = penetrations(recorded, substeps=1)
    assert found == [], [f.describe() for f in found]


def test_clear_table_puts_stored_items_back() -> None:
    with TrialRunner("c2") as runner:
        result = runner.run("opm", plan="clear-table", seed=0)
        positions = {n: runner.world.objects[n].position() for n in ("spoon", "cup")}
        joints = runner.world.world_joint_positions()
    print(result.order, result.failures, positions)
    assert result.success, result.failures
    setup = load_setup("c2")
    for name in ("spoon", "cup"):
        assert positions[name] == pytest.approx(setup.item(name).pose.xyz, abs=0.05)
    assert all(abs(v) < 1e-6 for v in joints.values())


def test_the_containment_factor_changes_the_opms_order_in_c1() -> None:
    orders = {}
    for c in ("1.0", "1.7"):
        result = run_cli("run", "c1", "--strategy", "opm", "--params", f"c={c}", "--json")
        data = json.loads(result.stdout)
        assert data["success"], data["failures"]
        orders[c] = data["order"]
    print(orders)
    assert orders["1.0"].index("cup") < orders["1.0"].index("breakfast-cereal")
    assert orders["1.7"].index("breakfast-cereal") < orders["1.7"].index("cup")


@pytest.mark.parametrize("old, new, field, message", [
    ("    surface: counter\n", "    in: oven\n", "items[0].in", "unknown container 'oven'"),
    ("    in: drawer_1\n    category: none\n    target: [-0.85",
     "    in: drawer_2\n    category: none\n    target: [-0.85", "items[0].pose",
     "does not fit in 'drawer_2'"),
    ("    in: drawer_1\n", "    in: drawer_1\n    contained: false\n", "items[0].contained",
     "follows from 'in:'"),
    ("  - name: milk\n    type: milk\n    pose: [-0.85, 1.75, 0.86, 0.0]\n    surface: island\n",
     "  - name: milk\n    type: milk\n    pose: [-0.85, 1.75, 0.86, 0.0]\n    surface: island\n"
     "    contained: true\n", "items[4].contained", "follows from 'in:'"),
    ("    in: drawer_1\n", "    in: drawer_1\n    surface: counter\n", "items[0].surface",
     "not both"),
])
def test_bad_storage_input_exits_2_naming_the_field(tmp_path: Path, old: str, new: str,
                                                   field: str, message: str) -> None:
    text = (Path(__file__).resolve().parents[1] / "worlds" / "setups" / "c2.yaml").read_text()
    if old == "    surface: counter\n":  # the first item of a copy of c1 instead
        text = (Path(__file__).resolve().parents[1] / "worlds" / "setups" / "c1.yaml") \
            .read_text().replace("    in: drawer_1\n", "    in: oven\n", 1)
        old = new = ""
    assert old in text
    path = tmp_path / "bad.yaml"
    path.write_text(text.replace(old, new, 1).replace("name: c2", "name: bad")
                    .replace("name: c1", "name: bad"))
    result = run_cli("show", str(path), "--out", str(tmp_path / "x.png"))
    print(result.stderr)
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert field in result.stderr and message in result.stderr


def test_kept_open_containers_are_closed_when_the_plan_ends(tmp_path: Path) -> None:
    trace = tmp_path / "t.jsonl"
    result = run_cli("run", "c2", "--keep-open", "--json", "--log", "--trace", str(trace))
    data = json.loads(result.stdout)
    assert data["success"], data["failures"]
    recorded = read_trace(trace)
    assert any(min(s["w"][:2]) > 0.3 for s in recorded.states)  # both drawers open at once
    assert recorded.states[-1]["w"] == [0.0, 0.0, 0.0]
    last_place = max(i for i, line in enumerate(data["log"]) if line.startswith("placed"))
    closes = [i for i, line in enumerate(data["log"]) if line.startswith("closed")]
    assert len(closes) == 2 and min(closes) > last_place  # by the plan, at its end


def test_an_open_door_is_drawn_on_the_map_by_its_outline_not_its_bounds() -> None:
    """A door swung open 2.3 rad spans a 44 x 39 cm square of axis-aligned bounds but is a
    2 cm plate: the base planner's map blocks the plate (and its margin) only."""
    from cramlite.designators.context import occupancy_map
    from cramlite.scene import PlanningScene

    scene = PlanningScene(load_setup("c1"))

    def door_outlines():
        return next(o for name, _, _, o in scene.environment_footprints()
                    if name == "cupboard_door")

    scene.set_world_joint("cupboard_door_joint", 2.3)
    (plate,) = door_outlines()
    lo, hi = scene.link_bounds("cupboard_door")
    grid = occupancy_map(scene)
    middle = plate.mean(axis=0)
    assert grid.blocked_at(np.array([middle]))[0]
    corners = np.array([[x, y] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])])
    # the corner of the bounds farthest from the plate, 5 cm in
    far = max(corners, key=lambda c: np.linalg.norm(plate - c, axis=1).min())
    inward = np.sign(middle - far) * 0.05
    assert not grid.blocked_at(np.array([far + inward]))[0]
    scene.set_world_joint("cupboard_door_joint", 0.0)
    assert door_outlines() is None  # closed: square to the axes


def test_clearing_up_opens_the_drawer_or_cupboard_before_taking_the_item() -> None:
    """Putting the spoon back into the cupboard (and the cup into its drawer), the goal's
    container is opened first, with both hands free: the handles would not move with a
    hand full (injected), and they are never asked to."""
    setup = Path(__file__).parent / "one_hand_cupboard.yaml"
    with TrialRunner(str(setup)) as runner:
        runner.modules = HandlesNeedBothHandsFree(runner.world)
        result = runner.run("opm", plan="clear-table")
        assert runner.modules.refused == 0
    assert result.success, result.failures
    for item in ("spoon", "cup"):
        node = next(n for n in result.actions
                    if n["name"] == "TransportAction" and n["object"] == item)
        steps = [(c["name"], c["status"]) for c in node["children"]]
        assert steps.index(("OpenAction", "succeeded")) < \
            steps.index(("PickUpAction", "succeeded")) < \
            steps.index(("PlaceAction", "succeeded")) < steps.index(("CloseAction", "succeeded"))


def test_a_container_the_free_hand_cannot_open_is_opened_with_both_hands_free(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Moving the cup from its drawer into the cupboard (taken out first: its drawer is
    opened and the cup picked up with the cupboard still closed), the handles do not move
    while a hand is full (injected at execution, after the hand has closed on the handle):
    the gripper lets go and backs off, the cup is put down, the cupboard opened with both
    hands free, and the cup fetched again and put in."""
    from cramlite.plans.report import PlanReport

    from cramlite import plans
    from cramlite.designators import ObjectDesignatorDescription, TransportAction

    def cup_into_cupboard(ctx, setup, strategy):
        TransportAction(ObjectDesignatorDescription(names=["cup"]), target=(1.40, 1.85, 1.0),
                        target_yaw=0.0).perform(ctx)
        return PlanReport(order=["cup"])

    monkeypatch.setitem(plans.PLANS, "cup-into-cupboard", cup_into_cupboard)
    setup = Path(__file__).parent / "one_hand_cupboard.yaml"
    with TrialRunner(str(setup)) as runner:
        runner.modules = HandlesNeedBothHandsFree(runner.world)
        result = runner.run("opm", plan="cup-into-cupboard")
        assert runner.modules.refused > 0
    assert not result.failures, result.failures  # (the other items stay where they are)
    x, y, z = result.items["cup"]["position"]
    assert math.dist((x, y), (1.40, 1.85)) < 0.02 and z > 0.99  # (on the cupboard's shelf)
    node = next(n for n in result.actions if n["name"] == "TransportAction")
    steps = [(c["name"], c["status"]) for c in node["children"]]
    failed = steps.index(("OpenAction", "failed"))
    assert steps.index(("PickUpAction", "succeeded")) < failed
    after = steps[failed + 1:]
    assert after.index(("PlaceAction", "succeeded")) < \
        after.index(("OpenAction", "succeeded")) < after.index(("PickUpAction", "succeeded"))
    assert steps[-1] == ("CloseAction", "succeeded")


def test_an_item_in_a_drawer_is_not_grasped_from_the_front() -> None:
    """The fingers of a front grasp would pass through a drawer's sides: an item lying in a
    drawer is offered grasps from above only; one in the cupboard or on the counter keeps
    its front grasps."""
    from cramlite.designators.actions import _grasps_in, grasps_of
    from cramlite.designators.storage import container_of

    with World.from_setup(load_setup("c1")) as world, simulated_robot(world) as ctx:
        drawer = container_of(ctx, "spoon")  # drawer_1
        bottom = world.objects["spoon"].aabb()[0][2]
        milk = grasps_of(ctx, "milk")
        assert {g.kind for g in milk} == {"front", "top"}
        assert {g.kind for g in _grasps_in(ctx, drawer, bottom, milk)} == {"top"}
        assert _grasps_in(ctx, None, bottom, milk) == milk  # on a counter: all of them
        for name in ("cup", "milk"):  # (in the cupboard, on the counter)
            lo, _ = world.objects[name].aabb()
            kept = _grasps_in(ctx, container_of(ctx, name), lo[2], grasps_of(ctx, name))
            assert "front" in {g.kind for g in kept}, name
