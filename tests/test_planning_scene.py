"""Planning on the planning scene: the robot checked against itself, nothing but the
process modules touching what executes, and a plan acting on what they report."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cramlite.backends import EXECUTION_CALLS, OBSERVATION_CALLS
from cramlite.backends.base import ProcessModules
from cramlite.designators import (
    MotionPlanningFailed,
    MoveArmJointsMotion,
    ParkArmsAction,
    simulated_robot,
)
from cramlite.designators.context import scene_collisions
from cramlite.scene.collision import HeldObject
from cramlite.trace import read_trace
from cramlite.trace.check import penetrations
from cramlite.trial import TrialRunner
from cramlite.world import load_setup
from cramlite.world.pr2 import PARK_JOINTS
from tests.conftest import needs_pybullet, run_cli

#: The right arm reaching across the chest, the left one parked: the right gripper 9 cm
#: inside the left shoulder's housing (found by a random search; the scene and the trace
#: check must both see it).
ACROSS = {"r_shoulder_pan_joint": 0.53, "r_shoulder_lift_joint": -0.37,
          "r_upper_arm_roll_joint": -1.55, "r_elbow_flex_joint": -2.17,
          "r_forearm_roll_joint": 0.1, "r_wrist_flex_joint": -0.85, "r_wrist_roll_joint": 2.53}
RIGHT = list(ACROSS)


def test_a_motion_into_the_robot_itself_is_refused_and_the_trace_check_finds_it(
        tmp_path: Path) -> None:
    with simulated_robot(load_setup("v1")) as ctx:
        ParkArmsAction().perform(ctx)
        check = ctx.collisions.check(RIGHT)
        goal = np.array([ACROSS[n] for n in RIGHT])
        contacts = check.contacts(goal)
        print([c.describe() for c in contacts])
        assert contacts and all(c.other.startswith("l_") for c in contacts)
        assert contacts[0].depth_m > 0.05 and "gripper" in contacts[0].what
        with pytest.raises(MotionPlanningFailed, match="inside l_shoulder_pan_link"):
            MoveArmJointsMotion(dict(ACROSS)).perform(ctx)
        now = ctx.scene.joint_positions(RIGHT)
        assert now == pytest.approx({n: PARK_JOINTS["right"][n] for n in RIGHT})  # not moved
    # a trace that goes there anyway (written by hand): the check reports the robot itself
    setup = load_setup("v1")
    trace = tmp_path / "across.jsonl"
    with TrialRunner(setup) as runner:
        result = runner.run("baseline", seed=0, trace=trace)
    assert result.success
    recorded = read_trace(trace)
    joints = recorded.header["joints"]
    state = {k: v for k, v in recorded.states[-1].items() if k != "end"}
    q = list(state["q"])
    for name, value in ACROSS.items():
        q[joints.index(name)] = value
    bad = tmp_path / "bad.jsonl"
    lines = trace.read_text().splitlines()  # (the end: the trace is cut short after it)
    bad.write_text("\n".join([lines[0], json.dumps(state), json.dumps({**state, "q": q,
                                                               "t": state["t"] + 1.0})]) + "\n")
    found = penetrations(read_trace(bad))
    print([f.describe() for f in found])
    mutual = [f for f in found if {f.what[:2], f.other[:2]} == {"r_", "l_"}]
    assert mutual and max(f.depth_m for f in mutual) > 0.05
    assert all(f.line == 3 or f.between for f in found)  # (the first state was clean)
    cli = run_cli("replay", str(bad), "--check")
    assert cli.returncode == 1 and "l_shoulder_pan_link" in cli.stdout


class Recording(ProcessModules):
    """Process modules that record every call made to them (and forward it), and know when
    an execution call is in progress."""

    def __init__(self, inner: ProcessModules):
        self.inner = inner
        self.calls: list[str] = []
        self.executing = False

    def __getattribute__(self, name):
        if name in EXECUTION_CALLS | OBSERVATION_CALLS:
            inner = object.__getattribute__(self, "inner")
            calls = object.__getattribute__(self, "calls")
            method = getattr(inner, name)

            def call(*args, **kwargs):
                calls.append(name)
                if name not in EXECUTION_CALLS:
                    return method(*args, **kwargs)
                self.executing = True
                try:
                    return method(*args, **kwargs)
                finally:
                    self.executing = False
            return call
        return object.__getattribute__(self, name)

    # (the abstract methods, for the ABC: every call goes through __getattribute__)
    execute_base_trajectory = execute_joint_trajectory = attach = detach = settle = None
    base_pose = joint_positions = world_joint_positions = object_pose = tool_pose = None
    release_all = None


@needs_pybullet
def test_planning_never_moves_the_world_that_executes(monkeypatch) -> None:
    """A trial through process modules that record every call: they see only execution
    and observation calls, and nothing moves a body of the PyBullet world but an execution
    call in progress."""
    from cramlite.backends.pybullet import bodies
    from cramlite.backends.pybullet import world as pybullet_world

    runner = TrialRunner("c1", backend="pybullet")
    recording = Recording(runner.modules)
    runner.modules = recording
    outside: list[str] = []

    def guarded(cls, name):
        original = getattr(cls, name)

        def wrapper(*args, **kwargs):
            if not recording.executing:
                outside.append(f"{cls.__name__}.{name}")
            return original(*args, **kwargs)
        monkeypatch.setattr(cls, name, wrapper)

    with runner:
        runner.backend.reset()  # (before the guards: resetting is the runner's, not a plan's)
        for cls, name in ((bodies.RobotBody, "set_base_pose"),
                          (bodies.RobotBody, "set_joint_positions"),
                          (bodies.WorldObject, "set_pose"),
                          (pybullet_world.World, "set_world_joint"),
                          (pybullet_world.World, "restore"),
                          (pybullet_world.World, "step")):
            guarded(cls, name)
        monkeypatch.setattr(runner.backend, "reset", lambda poses=None: None)
        result = runner.run("opm", seed=0)
    print(result.success, sorted(set(recording.calls)), outside[:5])
    assert result.success, result.failures
    assert set(recording.calls) <= EXECUTION_CALLS | OBSERVATION_CALLS
    assert {"execute_base_trajectory", "execute_joint_trajectory", "attach",
            "detach"} <= set(recording.calls)
    assert outside == []


@needs_pybullet
def test_a_plan_acts_on_what_the_process_modules_report() -> None:
    """The cup stands 3 cm off the spot the setup (the scene's first belief) says: the
    trial grasps it where it is (the gripper's tool frame on the cup's axis, as the
    simulator has them when the gripper closes) and puts it on its target."""
    setup = load_setup("v1")
    with TrialRunner(setup, backend="pybullet") as runner:
        real_reset = runner.backend.reset
        world = runner.world

        def moved_cup(poses=None):
            real_reset(poses)
            cup = world.objects["cup"]
            (x, y, z), orientation = cup.pose()
            cup.set_pose((x - 0.03, y, z), orientation)

        runner.backend.reset = moved_cup
        grasps = []
        real_attach = runner.modules.attach

        def attach(arm, obj):
            if obj == "cup":
                tool, _ = world.robot.link_pose(f"{arm[0]}_gripper_tool_frame")
                axis, _ = world.objects["cup"].pose()
                grasps.append(float(np.hypot(tool[0] - axis[0], tool[1] - axis[1])))
            real_attach(arm, obj)

        runner.modules.attach = attach
        assert runner.scene.initial.poses["cup"][0][0] == pytest.approx(1.45)
        result = runner.run("baseline", seed=0)
    print(result.failures, result.items["cup"], grasps)
    assert result.success, result.failures
    assert result.items["cup"]["off_target_m"] < 0.02
    assert grasps and max(grasps) < 0.005  # on the cup as it is, not 3 cm off


@pytest.mark.parametrize("trace, what, other, deeper_than", [
    ("audit-c3-fingertip-in-shoulder.jsonl", "l_gripper_r_finger_tip_link",
     "r_shoulder_pan_link", 0.08),
    ("audit-c1-wrist-in-upper-arm.jsonl", "l_upper_arm_link", "r_wrist_flex_link", 0.04)])
def test_the_audits_self_collisions_are_found_by_both_checks(trace: str, what: str, other: str,
                                                            deeper_than: float) -> None:
    """States recorded by cramlite before it checked the robot against itself (an audit
    found them: a fingertip 8 cm inside the other shoulder closing drawer_2 in c3, a wrist
    5 cm inside the other upper arm in c1): the trace check reports them, and the planning
    scene refuses those configurations."""
    from cramlite.scene import PlanningScene

    recorded = read_trace(Path(__file__).parent / "data" / trace)
    found = penetrations(recorded)
    print([f.describe() for f in found])
    assert any(f.what == what and f.other == other and f.depth_m > deeper_than
               for f in found)
    scene = PlanningScene(load_setup(recorded.header["setup"]))
    collisions = scene_collisions(scene)
    joints = recorded.header["joints"]
    worst = max(found, key=lambda f: f.depth_m)
    state = recorded.states[worst.line - 2]
    scene.belief.base = tuple(state["base"])
    names = [n for n in joints if n.startswith(("r_", "l_")) and "gripper" not in n]
    values = dict(zip(joints, state["q"], strict=True))
    scene.belief.joints.update(values)
    check = collisions.check(names, held=[])
    q = np.array([values[n] for n in names])
    assert not check.is_free(q)
    contacts = check.contacts(q)
    print([c.describe() for c in contacts])
    assert any({c.what, c.other} == {what, other} for c in contacts)


def test_a_handles_whole_path_is_checked_as_one_batch_with_the_container_moving() -> None:
    """`states_free_as_joint_moves` answers as `move_world_joint` then `is_free` state by
    state would: each state's obstacles are the kitchen with the drawer or door where it
    is then (and what lies in a drawer riding along), not where the check stands."""
    from cramlite.designators.motions import gripper_joints
    from cramlite.designators.storage import AccessingLocation, handle_width
    from cramlite.scene.gripper import gripper_geometry

    with simulated_robot(load_setup("c1")) as ctx:
        ParkArmsAction().perform(ctx)
        scene = ctx.scene
        drawer = next(c for c in scene.containers.values() if scene.riding_along(c.joint))
        door = next(c for c in scene.containers.values() if c.kind != "drawer")
        assert not scene.riding_along(door.joint)
        rng = np.random.default_rng(3)
        for container in (drawer, door):
            end = container.open_value / (3 if container is door else 1)
            access = next(AccessingLocation(container, 0.0, end).ground(ctx))
            closed = gripper_geometry().closing_angle(handle_width(scene, container))

            def check(access=access, container=container, closed=closed):
                return ctx.collisions.check(
                    list(access.names), ignore=(container.handle,), base=access.base,
                    fixed=gripper_joints(access.arm, "close", closed))

            batch, values, states = check(), access.values, access.states
            # each state's world as move_world_joint makes it, items riding along
            moving = batch._obstacles_by_state(container.joint, values)
            one = check()
            for i in (0, len(values) // 2, len(values) - 1):
                one.move_world_joint(container.joint, float(values[i]))
                np.testing.assert_array_equal(moving.placements[i], one._placements)
                np.testing.assert_array_equal(moving.lo[i], one._lo)
            # free along the handle only with the container moving along
            assert batch.states_free_as_joint_moves(container.joint, values, states)
            opened = check()
            opened.move_world_joint(container.joint, float(values[-1]))
            assert not opened.states_free(states)  # (the hand in it where it was closed)
            assert not batch.states_free_as_joint_moves(container.joint, values[::-1], states)
            # and the same answers as state by state on states pushed off the path
            answers = set()
            for scale in (0.01, 0.03, 0.1, 0.3):
                pushed = states + rng.normal(0.0, scale, states.shape)
                alone = check()
                expected = True
                for q, value in zip(pushed, values, strict=True):
                    alone.move_world_joint(container.joint, float(value))
                    if not alone.is_free(q):
                        expected = False
                        break
                assert batch.states_free_as_joint_moves(container.joint, values,
                                                        pushed) == expected
                answers.add(expected)
            print(container.name, answers)
            assert False in answers


def test_the_z_rows_of_links_rotations_are_those_of_their_frames() -> None:
    """`BatchedFrames.z_rows` (what an upright item's tilt is asked of) gives the bottom
    rows of the links' world rotations that `frames` gives, for every link of the robot,
    whatever the base's heading."""
    from cramlite.scene.kinematics import BatchedFrames
    from cramlite.scene.models import pr2_model
    from cramlite.scene.transforms import planar

    model = pr2_model()
    batched = BatchedFrames(model)
    links = tuple(model.link_frames)
    rng = np.random.default_rng(2)
    for _ in range(5):
        state = rng.uniform(-1.5, 1.5, len(RIGHT))
        q = model.q({})
        frames = batched.frames(planar(0.3, -0.2, float(rng.uniform(-3, 3))), q, RIGHT,
                                state[None], links)
        rows = batched.z_rows(q.copy(), RIGHT, state, links)
        np.testing.assert_allclose(rows, frames[0, :, 2, :3], atol=1e-12)


def test_the_nesting_prefilter_asks_of_each_part_where_it_is() -> None:
    """Before the exact test of one shape wholly inside another, the check asks whether the
    point `enclosed` tests of one lies in the other's bounds: that point must be where the
    part is in that state (its shape's point, placed by the part's frame), for robot
    links and a held item alike, in a batch of states."""
    from cramlite.scene.collision import _reference_point

    with simulated_robot(load_setup("v1")) as ctx:
        robot = ctx.scene.robot
        names = ["torso_lift_joint", *(n for n in robot.joints if n.startswith("r_")
                                       and "gripper" not in n)]
        for held in ([], [HeldObject("milk", "right", np.eye(4))]):
            check = ctx.collisions.check(names, held=held)
            rng = np.random.default_rng(4)
            lows = np.array([max(robot.joints[n].lower, -np.pi) for n in names])
            highs = np.array([min(robot.joints[n].upper, np.pi) for n in names])
            states = rng.uniform(lows, highs, size=(12, len(names)))
            frames = check._link_frames(states)
            _, _, boxes = check._near(frames)
            placements = check._placements
            obstacle_refs = [placements[k][:3, :3] @ _reference_point(o.shape) +
                             placements[k][:3, 3] for k, o in enumerate(check.obstacles)]
            asked = 0
            for s in range(len(states)):
                part_obstacle, part_part = check._nested_test(tuple(b[s] for b in boxes))
                centres, spans = boxes[0][s], boxes[1][s]
                refs = []
                for p, part in enumerate(check.parts):
                    placed = frames[s][check._rows[p]] @ check._in_frame[p]
                    refs.append(placed[:3, :3] @ _reference_point(part.shape) + placed[:3, 3])
                for p in range(len(check.parts)):
                    for k in range(len(check.obstacles)):
                        expected = bool((check._lo[k] <= refs[p]).all() and
                                        (refs[p] <= check._hi[k]).all() or
                                        (np.abs(obstacle_refs[k] - centres[p]) <= spans[p]).all())
                        assert part_obstacle(p, k) == expected
                        asked += expected
                    j = int(rng.integers(len(check.parts)))
                    expected = bool((np.abs(refs[p] - centres[j]) <= spans[j]).all() or
                                    (np.abs(refs[j] - centres[p]) <= spans[p]).all())
                    assert part_part(p, j) == expected
            assert asked > 20  # (the draw does reach into bounds)
