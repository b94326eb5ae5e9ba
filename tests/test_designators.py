"""Each designator type executing in a real PyBullet world (planned on the planning
scene, which observes it), fall-through, and the plan language."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.conftest import skip_module_without_pybullet

skip_module_without_pybullet()

from cramlite.backends.pybullet.client import p
from cramlite.backends.pybullet.world import World
from cramlite.designators import (
    CostmapLocation,
    MoveTorsoAction,
    NavigateAction,
    NavigationFailed,
    ObjectDesignatorDescription,
    ObjectNotFound,
    ObjectUnreachable,
    ParkArmsAction,
    PickUpAction,
    PlaceAction,
    PlacingLocation,
    PlanFailure,
    Sequential,
    TransportAction,
    TryInOrder,
    simulated_robot,
)
from cramlite.designators.actions import grasps_of
from cramlite.designators.motions import AttachMotion, MoveArmJointsMotion, gripper_joints
from cramlite.motion.ik import arm_ik, tool_frame
from cramlite.scene.gripper import gripper_geometry
from cramlite.world import load_setup
from tests.injected import NavigationFailsOnce


@pytest.fixture
def world():
    with World.from_setup(load_setup("v1")) as w:
        yield w


def test_object_designators(world) -> None:
    with simulated_robot(world) as ctx:
        cup = ObjectDesignatorDescription(names=["cup"]).resolve(ctx)
        assert cup.name == "cup" and cup.type == "cup"
        assert cup.pose(ctx)[0] == pytest.approx((1.45, 0.85, 0.85), abs=2e-3)
        by_type = [o.name for o in ObjectDesignatorDescription(types=["bowl", "milk"]).ground(ctx)]
        assert sorted(by_type) == ["bowl", "milk"]
        with pytest.raises(ObjectNotFound, match="teapot"):
            ObjectDesignatorDescription(names=["teapot"]).resolve(ctx)


def test_costmap_location_offers_checked_reachable_poses(world) -> None:
    with simulated_robot(world) as ctx:
        ParkArmsAction().perform(ctx)
        MoveTorsoAction(0.25).perform(ctx)
        # the cup right beside the milk: many arms that reach the milk would hit the cup
        world.objects["cup"].set_pose((1.45, -0.0625, 0.85))  # (1 cm beside it)
        ctx.observe()  # (the scene learns where it is now)
        position, orientation = world.objects["milk"].pose()
        location = CostmapLocation(position, grasps_of(ctx, "milk", ["front"]), "milk",
                                   orientation=orientation)
        poses = list(location.ground(ctx))  # all it offers (up to its IK budget)
        print(location.rejected)
        assert location.rejected["arm collision"] > 0
        assert len(poses) >= 8 and len({(p.base, p.arm) for p in poses}) == len(poses)
        parked = ctx.scene.joint_positions()  # (the other arm stays parked)
        for pose in poses:
            assert ctx.checker.is_free(*pose.base)
            world.robot.set_base_pose(*pose.base)
            world.robot.set_joint_positions(parked)
            world.robot.set_joint_positions(pose.joints)
            tool, _ = world.robot.link_pose(tool_frame(pose.arm))
            assert math.dist(tool, (position[0], position[1], position[2] + 0.1)) < 0.005
            # pre-grasp and grasp (the fingers open around it) touch nothing, the milk
            # included; at the lift, the milk in hand touches nothing either
            for joints, holding in ((pose.pre_joints, False), (pose.joints, False),
                                    (pose.post_joints, True)):
                world.robot.set_joint_positions(joints)
                closed = gripper_geometry().closing_angle(pose.grasp.width_m)
                world.robot.set_joint_positions(  # (open on the way, closed on it held)
                    gripper_joints(pose.arm, "close" if holding else "open", closed))
                if holding:
                    tool = world.robot.link_pose(tool_frame(pose.arm))
                    world.objects["milk"].set_pose(*p.multiplyTransforms(*tool, *pose.relative))
                found = deepest_contacts(world, set() if not holding else {"milk"})
                if holding:
                    found |= deepest_contacts(world, set(), body=world.objects["milk"].body)
                print(pose.describe(), found)
                assert all(depth <= 0.01 for depth in found.values()), found
            world.objects["milk"].set_pose(position, orientation)


def deepest_contacts(world, allowed: set[str], body: int | None = None) -> dict[str, float]:
    """Penetration depth of the robot (or another body) into the kitchen and the items but
    `allowed` (an independent, whole-body check with PyBullet). PyBullet gives a robot's
    mesh link its convex hull, which fills the mesh's hollows (the PR2's forearm's hull
    reaches 2.4 cm below the mesh): where it finds a robot link more than 1 cm into the
    kitchen's boxes, the depth is that of the link's own mesh (coal, exact), as far as it
    is more than 1 cm."""
    body = world.robot.body if body is None else body
    out = {}
    others = {"kitchen": world.environment} | {n: o.body for n, o in world.objects.items()
                                               if n not in allowed and o.body != body}
    for name, other in others.items():
        points = p.getClosestPoints(body, other, 0.0, physicsClientId=world.client)
        depths = []
        for pt in points:
            depth = -pt[8]
            if depth > 0.01 and body == world.robot.body and other == world.environment:
                depth = 0.01 if not _mesh_deeper_than(world, pt[3], pt[4], 0.01) else depth
            if depth > 0.01:
                print("DEEP", name, pt[3], pt[4], depth, pt[5])
            depths.append(depth)
        out[name] = max(depths, default=0.0)
    return out


def _mesh_deeper_than(world, robot_link: int, kitchen_link: int, depth_m: float) -> bool:
    """Is a robot link's own collision mesh (not PyBullet's convex hull of it) more than
    `depth_m` inside one of a kitchen link's boxes? (A box shrunk by `depth_m` on every
    side that the exact mesh meets: coal.)"""
    import coal
    import pinocchio as pin

    from cramlite.scene.models import pr2_model

    client = world.client
    name = p.getJointInfo(world.robot.body, robot_link, physicsClientId=client)[12].decode()
    frame = p.getLinkState(world.robot.body, robot_link, computeForwardKinematics=True,
                           physicsClientId=client)[4:6]  # (the URDF link's own frame)
    link = pin.XYZQUATToSE3(np.array([*frame[0], *frame[1]]))
    kitchen = p.getLinkState(world.environment, kitchen_link, physicsClientId=client)[0:2]
    model = pr2_model()
    meshes = [go for go in model.geometry_model.geometryObjects
              if model.model.frames[go.parentFrame].name == name]
    assert meshes, name
    for shape in p.getCollisionShapeData(world.environment, kitchen_link,
                                         physicsClientId=client):
        assert shape[2] == p.GEOM_BOX, shape  # (the kitchen's furniture: boxes)
        centre = p.multiplyTransforms(*kitchen, shape[5], shape[6])
        box = coal.Box(*(max(1e-6, size - 2 * depth_m) for size in shape[3]))
        placed = pin.XYZQUATToSE3(np.array([*centre[0], *centre[1]]))
        for go in meshes:
            in_link = model.model.frames[go.parentFrame].placement.actInv(go.placement)
            mesh = link * in_link
            result = coal.CollisionResult()
            coal.collide(go.geometry, coal.Transform3s(mesh.rotation, mesh.translation), box,
                         coal.Transform3s(placed.rotation, placed.translation),
                         coal.CollisionRequest(), result)
            if result.isCollision():
                return True
    return False


def test_costmap_location_is_empty_for_an_unreachable_point(world) -> None:
    with simulated_robot(world) as ctx:
        behind_counter = (1.8, 0.0, 0.85)  # back of the counter: no base pose reaches it
        location = CostmapLocation(behind_counter, grasps_of(ctx, "milk", ["front"]), "milk")
        assert list(location.ground(ctx)) == []
        assert "base inside fixed geometry" in location.describe_rejections()


def test_placing_location_avoids_occupied_spots_and_respects_yaw(world) -> None:
    with simulated_robot(world) as ctx:
        cup = ObjectDesignatorDescription(names=["cup"]).resolve(ctx)
        occupied = world.objects["milk"].position()  # the milk's spot on the counter
        spots = list(PlacingLocation(cup, target=occupied).ground(ctx))
        assert spots == []
        free = list(PlacingLocation(cup, surface="counter", preferred=occupied).ground(ctx))
        assert free and math.dist(free[0][:2], occupied[:2]) > 0.08
        cereal = ObjectDesignatorDescription(names=["breakfast-cereal"]).resolve(ctx)
        # 12 cm beside the milk (7.5 cm wide) along y: the 19 cm wide side of the cereal
        # box would overlap it; turned by 90 degrees (7 cm along y) it keeps 4.75 cm clear
        beside_milk = (1.45, -0.15 + 0.12, 0.85)
        placing = PlacingLocation(cereal, target=beside_milk)
        assert not placing.is_free(ctx, beside_milk, 0.0)
        assert placing.is_free(ctx, beside_milk, math.pi / 2)


def test_motions_move_attached_objects_with_the_gripper(world) -> None:
    with simulated_robot(world) as ctx:
        ParkArmsAction().perform(ctx)
        world.robot.set_base_pose(0.5, 0.85 + 0.188, 0.0)
        tool, _ = world.robot.link_pose(tool_frame("right"))
        # (the cup between the fingers, its bottom 3 cm below them: a gripper holds only
        # what it reaches)
        world.objects["cup"].set_pose((tool[0], tool[1], tool[2] - 0.03), (0, 0, 0, 1))
        ctx.observe()
        AttachMotion("right", "cup").perform(ctx)
        before = np.array(world.objects["cup"].position())
        tool_before = np.array(world.robot.link_pose(tool_frame("right"))[0])
        arm_before = ctx.arm_s
        MoveArmJointsMotion({"torso_lift_joint": 0.2}).perform(ctx)
        moved = np.array(world.objects["cup"].position()) - before
        tool_moved = np.array(world.robot.link_pose(tool_frame("right"))[0]) - tool_before
        assert moved == pytest.approx(tool_moved, abs=1e-6)
        assert moved[2] == pytest.approx(0.2, abs=1e-3)
        # the PR2's torso: 1.3 cm/s, and a quarter second to reach that speed
        assert ctx.arm_s - arm_before == pytest.approx(0.2 / 0.013 + 0.25, rel=0.01)


def test_move_tcp_motion_reaches_a_pose_or_fails_typed(world) -> None:
    import pinocchio as pin

    from cramlite.designators import MoveTCPMotion

    with simulated_robot(world) as ctx:
        world.robot.set_base_pose(0.0, 0.0, 0.0)
        ctx.observe()
        ParkArmsAction().perform(ctx)
        target = pin.SE3(np.eye(3), np.array([0.6, -0.2, 1.0]))
        MoveTCPMotion("right", target).perform(ctx)
        tool, _ = world.robot.link_pose(tool_frame("right"))
        assert tool == pytest.approx((0.6, -0.2, 1.0), abs=2e-3)
        with pytest.raises(ObjectUnreachable, match="no IK solution"):
            MoveTCPMotion("right", pin.SE3(np.eye(3), np.array([2.0, 0.0, 1.0]))).perform(ctx)


def test_actions_pick_and_place_step_by_step(world) -> None:
    with simulated_robot(world, seed=3) as ctx:
        ParkArmsAction().perform(ctx)
        MoveTorsoAction(0.25).perform(ctx)
        assert world.robot.joint_positions(["torso_lift_joint"])["torso_lift_joint"] == \
            pytest.approx(0.25)
        NavigateAction((0.85, 0.35 + 0.188, 0.0)).perform(ctx)  # in front of the spoon
        assert ctx.base_path_m > 2.0
        arm = PickUpAction("spoon", arms=["right"]).perform(ctx)
        assert ctx.holding[arm].obj == "spoon"
        assert world.objects["spoon"].position()[2] > 0.9  # lifted off the counter
        # (the arm parks on the way to the next drive: here the place's first arm motion
        # runs the park alone first)
        assert [d.trajectory.names[0][:2] for d in ctx.deferred] == ["r_"]
        PlaceAction("spoon", (1.45, 0.2, 0.85)).perform(ctx)
        assert not ctx.holding
        assert world.objects["spoon"].position() == pytest.approx((1.45, 0.2, 0.85), abs=0.01)


def test_navigate_fails_typed_when_there_is_no_path(world) -> None:
    with simulated_robot(world) as ctx, pytest.raises(NavigationFailed, match="no collision"):
        NavigateAction((1.5, 0.0, 0.0)).perform(ctx)  # inside the counter


def test_transport_moves_an_object_to_its_target(world) -> None:
    with simulated_robot(world, seed=1) as ctx:
        TransportAction("bowl", target=(-0.85, 1.24, 0.86)).perform(ctx)
        assert world.objects["bowl"].position() == pytest.approx((-0.85, 1.24, 0.86), abs=0.05)
        assert not ctx.holding


def test_transport_falls_through_to_the_next_candidate(world) -> None:
    with simulated_robot(world, seed=1) as ctx:
        ctx.modules = NavigationFailsOnce(world)
        TransportAction("cup", target=(-1.0, 1.1, 0.86)).perform(ctx)
        assert ctx.modules.refused == 1
        assert world.objects["cup"].position() == pytest.approx((-1.0, 1.1, 0.86), abs=0.05)
        print(ctx.log)


def test_transport_failure_says_what_was_tried(world) -> None:
    with simulated_robot(world) as ctx:
        world.objects["milk"].set_pose((1.8, -0.15, 0.85))  # back of the counter
        ctx.observe()
        with pytest.raises(ObjectUnreachable) as info:
            TransportAction("milk", target=(-0.85, 1.6, 0.86)).perform(ctx)
        failure = info.value
        assert failure.object == "milk" and failure.tried
        assert "base poses" in failure.tried[-1]
        assert failure.as_dict()["type"] == "ObjectUnreachable"


def test_plan_language() -> None:
    calls = []

    def ok(name):
        return lambda ctx: calls.append(name) or name

    def fail(name):
        def step(ctx):
            calls.append(name)
            raise ObjectUnreachable(f"{name} failed", obj="x")
        return step

    assert Sequential([ok("a"), ok("b")]).perform(None) == ["a", "b"]
    assert TryInOrder([fail("c"), ok("d"), ok("e")]).perform(None) == "d"
    with pytest.raises(ObjectUnreachable) as info:
        TryInOrder([fail("f"), fail("g")], describe=lambda s: "alt").perform(None)
    assert len(info.value.tried) == 2 and isinstance(info.value, PlanFailure)
    with pytest.raises(ObjectUnreachable):
        Sequential([ok("h"), fail("i"), ok("never")]).perform(None)
    assert calls == ["a", "b", "c", "d", "f", "g", "h", "i"]


def test_ik_solver_is_shared_not_rebuilt(world) -> None:
    solver = arm_ik("left")
    with simulated_robot(world) as ctx:
        TransportAction("cup", target=(-1.0, 1.1, 0.86)).perform(ctx)
    assert arm_ik("left") is solver
