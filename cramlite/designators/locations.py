"""Location designators: many candidates, best first, each checked before it is offered.

`CostmapLocation`: base poses from which an arm reaches a point with a grasp. Candidates
lie on rings around the point, facing it, with the arm's shoulder in line; they are
scored by stand-off (close to the arm's sweet spot) and by how far the robot would have
to drive, then checked in that order: footprint free in the 2D map, IK solutions for
the grasp and pre-grasp, and no arm link inside fixed geometry or another item.

`PlacingLocation`: where an object may be put: at a target (then small offsets within
the placing tolerance), or on free spots of a surface, nearest to a preferred point.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from cramlite.designators.context import RobotContext
from cramlite.designators.grasps import PREGRASP_OFFSET_M, in_base_frame, tool_pose
from cramlite.designators.objects import ObjectDesignator
from cramlite.motion.ik import ARMS, arm_ik
from cramlite.world.bodies import quat_yaw
from cramlite.world.bullet import p
from cramlite.world.pr2 import TORSO_UP_M

BasePose = tuple[float, float, float]
Vec3 = tuple[float, float, float]
SHOULDER_OFFSET_M = 0.188  # lateral offset of each shoulder from the base centre
STANDOFFS_M = tuple(round(0.45 + 0.025 * i, 3) for i in range(15))  # 0.45 .. 0.80
IDEAL_STANDOFF_M = 0.60
TRAVEL_WEIGHT = 0.25
ARM_PENETRATION_TOLERANCE_M = 0.01


@dataclass(frozen=True)
class ReachablePose:
    """A base pose with the arm, grasp and joint angles that reach the point from it."""

    base: BasePose
    arm: str
    grasp: str
    joints: dict[str, float]
    pre_joints: dict[str, float]

    def describe(self) -> str:
        x, y, yaw = self.base
        return f"base ({x:.2f}, {y:.2f}, {math.degrees(yaw):.0f} deg) {self.arm} arm {self.grasp}"


class CostmapLocation:
    """Base poses from which one of `arms` reaches `point` (an object's bottom centre)
    with one of the grasps in `grasp_heights` (grasp -> tool height above the point,
    in order of preference)."""

    def __init__(self, point: Vec3, grasp_heights: Mapping[str, float],
                 arms: Sequence[str] = ARMS, ignore: Sequence[str] = (),
                 angle_step_deg: float = 10.0, max_ik_checks: int = 24):
        self.point = point
        self.grasp_heights = dict(grasp_heights)
        self.arms = list(arms)
        self.grasps = list(self.grasp_heights)
        self.ignore = set(ignore)
        self.angle_step_deg = angle_step_deg
        self.max_ik_checks = max_ik_checks
        self.rejected: dict[str, int] = {"footprint": 0, "ik": 0, "arm collision": 0}

    def candidates(self, ctx: RobotContext) -> list[tuple[float, BasePose, str, str]]:
        here = ctx.modules.base_pose()
        px, py, _ = self.point
        out = []
        for arm in self.arms:
            side = 1.0 if arm == "right" else -1.0
            for standoff in STANDOFFS_M:
                for step in range(round(360 / self.angle_step_deg)):
                    yaw = math.radians(step * self.angle_step_deg) - math.pi
                    ux, uy = math.cos(yaw), math.sin(yaw)
                    x = px - standoff * ux - side * SHOULDER_OFFSET_M * uy
                    y = py - standoff * uy + side * SHOULDER_OFFSET_M * ux
                    score = (abs(standoff - IDEAL_STANDOFF_M)
                             + TRAVEL_WEIGHT * math.dist((x, y), here[:2]))
                    for rank, grasp in enumerate(self.grasps):
                        out.append((score + 0.05 * rank, (x, y, yaw), arm, grasp))
        out.sort(key=lambda c: c[0])
        return out

    def ground(self, ctx: RobotContext) -> Iterator[ReachablePose]:
        """Checked candidates, best first (lazily: work is done as they are asked for)."""
        ik_checks = 0
        for _, base, arm, grasp in self.candidates(ctx):
            if not ctx.checker.is_free(*base):
                self.rejected["footprint"] += 1
                continue
            if ik_checks >= self.max_ik_checks:
                return
            ik_checks += 1
            solution = self.reach_from(ctx, base, arm, grasp)
            if solution is None:
                self.rejected["ik"] += 1
                continue
            if not arm_clear(ctx, base, solution.joints, self.ignore):
                self.rejected["arm collision"] += 1
                continue
            yield solution

    def reach_from(self, ctx: RobotContext, base: BasePose, arm: str,
                   grasp: str) -> ReachablePose | None:
        """IK for the grasp and pre-grasp from one base pose (None if out of reach)."""
        ik = arm_ik(arm)
        seed = ctx.modules.joint_positions(ik.joint_names)
        height = self.grasp_heights[grasp]
        target = tool_pose(grasp, self.point, height, base[2])
        solution = ik.solve(in_base_frame(target, base), ctx.rng, seed,
                            preferred_torso_m=TORSO_UP_M)
        if solution is None:
            return None
        pre = tool_pose(grasp, self.point, height, base[2], PREGRASP_OFFSET_M)
        pre_solution = ik.solve(in_base_frame(pre, base), ctx.rng, solution.joints,
                                preferred_torso_m=solution.joints.get("torso_lift_joint"))
        if pre_solution is None:
            return None
        return ReachablePose(base, arm, grasp, solution.joints, pre_solution.joints)

    def describe_rejections(self) -> str:
        """What was checked and why it failed, for failure messages."""
        total = sum(self.rejected.values())
        if not total:
            return ""
        why = {"footprint": "base inside fixed geometry", "ik": "out of the arm's reach (IK)",
               "arm collision": "arm would hit something"}
        parts = ", ".join(f"{n} {why[k]}" for k, n in self.rejected.items() if n)
        return (f"{total} base poses {STANDOFFS_M[0]:.2f}-{STANDOFFS_M[-1]:.2f} m away "
                f"({'/'.join(self.arms)} arm, {'/'.join(self.grasps)} grasp): {parts}")


def arm_clear(ctx: RobotContext, base: BasePose, joints: dict[str, float],
              ignore: set[str]) -> bool:
    """No robot link penetrates fixed geometry or an item (other than `ignore`) when the
    robot stands at `base` with `joints` (checked in the world, then restored)."""
    world, robot = ctx.world, ctx.world.robot
    saved_base = robot.base_pose()
    saved = robot.joint_positions(list(joints))
    robot.set_base_pose(*base)
    robot.set_joint_positions(joints)
    try:
        p.performCollisionDetection(physicsClientId=world.client)
        others = [world.environment] + [o.body for n, o in world.objects.items()
                                        if n not in ignore and n not in held(ctx)]
        for body in others:
            points = p.getClosestPoints(robot.body, body, 0.0, physicsClientId=world.client)
            if any(pt[8] < -ARM_PENETRATION_TOLERANCE_M for pt in points):
                return False
        return True
    finally:
        robot.set_base_pose(*saved_base)
        robot.set_joint_positions(saved)


def held(ctx: RobotContext) -> set[str]:
    return {h.obj for h in ctx.holding.values()}


class PlacingLocation:
    """Free places for an object: at `target` (and offsets around it within the placing
    tolerance), or anywhere on `surface`, nearest to `preferred` first."""

    def __init__(self, obj: ObjectDesignator, target: Vec3 | None = None,
                 surface: str | None = None, preferred: Vec3 | None = None,
                 spot_spacing_m: float = 0.08, edge_margin_m: float = 0.06,
                 clearance_m: float = 0.01):
        if (target is None) == (surface is None):
            raise ValueError("give either a target or a surface")
        self.obj = obj
        self.target = target
        self.surface = surface
        self.preferred = preferred
        self.spot_spacing_m = spot_spacing_m
        self.edge_margin_m = edge_margin_m
        self.clearance_m = clearance_m

    def spots(self, ctx: RobotContext) -> list[Vec3]:
        if self.target is not None:
            tx, ty, tz = self.target
            rings = [(0.0, 1)] + [(r, 8) for r in (0.015, 0.03)]
            return [(tx + r * math.cos(2 * math.pi * k / n), ty + r * math.sin(2 * math.pi * k / n),
                     tz) for r, n in rings for k in range(n)]
        surf = ctx.world.surface(self.surface)
        margin = self.edge_margin_m + self.obj.radius_m(ctx)
        xs = np.arange(surf.x_min + margin, surf.x_max - margin + 1e-9, self.spot_spacing_m)
        ys = np.arange(surf.y_min + margin, surf.y_max - margin + 1e-9, self.spot_spacing_m)
        pref = self.preferred or ((surf.x_min + surf.x_max) / 2, (surf.y_min + surf.y_max) / 2,
                                  surf.top_z)
        spots = [(float(x), float(y), surf.top_z) for x in xs for y in ys]
        spots.sort(key=lambda s: math.dist(s[:2], pref[:2]))
        return spots

    def ground(self, ctx: RobotContext) -> Iterator[Vec3]:
        """Spots where the object fits at its most favourable yaw (the exact check, for
        the yaw it will have, is `is_free`)."""
        width = min(object_size(ctx, self.obj.name))
        others = self._others(ctx)
        for spot in self.spots(ctx):
            disc = rectangle(spot[:2], (width, width), 0.0)
            if not any(rectangles_overlap(disc, other, self.clearance_m) for other in others):
                yield spot

    def is_free(self, ctx: RobotContext, spot: Vec3, yaw: float) -> bool:
        """Does the object, put at `spot` with `yaw`, keep clear of every other item?
        (A round object's yaw does not matter.)"""
        if self.obj.is_round(ctx):
            yaw = 0.0
        mine = rectangle(spot[:2], object_size(ctx, self.obj.name), yaw)
        return not any(rectangles_overlap(mine, other, self.clearance_m)
                       for other in self._others(ctx))

    def _others(self, ctx: RobotContext) -> list[np.ndarray]:
        out = []
        for name, obj in ctx.world.objects.items():
            if name == self.obj.name or name in held(ctx):
                continue
            (x, y, _), orn = obj.pose()
            yaw = 0.0 if obj.is_round() else quat_yaw(orn)
            out.append(rectangle((x, y), object_size(ctx, name), yaw))
        return out


def object_size(ctx: RobotContext, name: str) -> tuple[float, float]:
    """Footprint (x, y extent in the object's own frame), however it is held now."""
    extents = ctx.world.objects[name].extents
    return extents[0], extents[1]


def rectangle(centre: Sequence[float], size: tuple[float, float], yaw: float) -> np.ndarray:
    """Corners (4 x 2) of a rectangle of `size` centred at `centre`, turned by `yaw`."""
    c, s = math.cos(yaw), math.sin(yaw)
    hx, hy = size[0] / 2, size[1] / 2
    local = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
    return local @ np.array([[c, s], [-s, c]]) + np.asarray(centre[:2])


def rectangles_overlap(a: np.ndarray, b: np.ndarray, clearance: float = 0.0) -> bool:
    """Separating-axis test: True unless some edge normal separates them by `clearance`."""
    for poly in (a, b):
        for i in range(4):
            edge = poly[(i + 1) % 4] - poly[i]
            axis = np.array([-edge[1], edge[0]]) / np.hypot(*edge)
            pa, pb = a @ axis, b @ axis
            if pa.min() >= pb.max() + clearance or pb.min() >= pa.max() + clearance:
                return False
    return True
