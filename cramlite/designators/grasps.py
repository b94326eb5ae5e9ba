"""Grasps a PR2 gripper can make: where the tool frame goes relative to an item, and how
far the fingers close.

A grasp is offered only where the item's width across the fingers fits the gripper's
opening with `CLEARANCE_M` to spare on each side (the fingers approach open, clear of the
item), and the fingers close until they touch (`GripperGeometry.closing_angle`):

- `front`: a horizontal approach, the tool frame at the item's middle height (capped),
  the fingers across a side that fits (a box across either horizontal side that does, a
  cylinder across its diameter); an item deeper than the hand is held by its near edge
  (its far part sticks out beyond the fingertips, clear of the palm).
- `top`: from above (the tool's x pointing down), the fingers around the item's top, or
  around the whole of a flat item, the fingertips just above the surface it lies on.
- `rim`: from above, the fingers astride the wall of a hollow item (a bowl), at the rim
  point the arm reaches best.

Which kinds an item allows, and how it turns (its yaw symmetry), come from its item file
(`cramlite.world.item_types`). `Grasp.yaws` are the tool's yaws relative to the item's
(None: any): a front grasp is used only where such a yaw is within `FRONT_MAX_TURN_RAD` of
the robot's heading.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from cramlite.errors import SetupError
from cramlite.scene.gripper import gripper_geometry
from cramlite.scene.models import BOX, CYLINDER, ItemModel

GRASPS = ("front", "top", "rim")
#: The open fingers keep at least this much off the item on each side as they approach.
CLEARANCE_M = 0.005
FRONT_GRASP_MAX_HEIGHT_M = 0.12
#: An item reaches at most this far in front of the palm into the hand.
PALM_CLEARANCE_M = 0.01
#: A top grasp holds at most this much of the item's top between the fingers, and keeps
#: the fingertips this far above the surface the item stands on.
TOP_GRIP_M = 0.035
FINGERTIP_FLOOR_M = 0.005
#: A rim grasp's fingers cross a flat wall at most this far off its middle (see
#: `Grasp._square_to_a_wall`; 6 degrees: fingertips ~1.65 mm inside the bowl, 2 mm at
#: about 8: the IK's rotation tolerance, 0.6 degrees, stays within the limit).
RIM_MAX_SQUINT_RAD = math.radians(6.0)
#: A rim grasp's fingertips reach this far below the rim.
RIM_GRIP_M = 0.03
#: A front grasp's tool yaw may differ from the robot's heading by at most this.
FRONT_MAX_TURN_RAD = math.radians(45)
#: Pre-grasp and retreat: back off along the approach (up, for a top grasp), and rise a
#: little too, so the gripper is clear of the surface and the neighbours on its way to
#: and from the carry or park pose.
PREGRASP_OFFSET_M = 0.10
PREGRASP_RISE_M = 0.04
RETREAT_RISE_M = 0.08
#: Lift after grasping, and height above the place pose from which an object is lowered.
LIFT_M = 0.08
#: Where a carried object is held while driving (robot frame): in front of the shoulder,
#: its bottom above every counter, upright as it was grasped (the tucked park pose would
#: tilt it and hang it into the furniture). A front grasp turns the tool toward the
#: robot's midline (pointing forward, the PR2's long gripper cannot hold it this close).
CARRY_X_M = 0.35
CARRY_Y_M = 0.20
CARRY_BOTTOM_Z_M = 1.03
#: Lower carry heights tried where the arm cannot hold an item that high (a tall item held
#: at its top): still above the counters (0.86 m).
CARRY_LOWER_BOTTOMS_M = (0.96, 0.90)


@dataclass(frozen=True)
class Grasp:
    """One way to hold an item (see the module's doc)."""

    kind: str  #: front | top | rim
    height_m: float  #: the tool point above the item's bottom
    width_m: float  #: the item's width between the fingers
    #: Tool yaws relative to the item's (radians); None: any.
    yaws: tuple[float, ...] | None
    #: The tool point relative to the item's centre, in the frame turned by the tool's
    #: yaw: (-inset, 0) for a front grasp by the near edge, (0, radius) at a rim.
    offset: tuple[float, float] = (0.0, 0.0)
    #: A rim of flat walls: a ring of `rim_sides` boxes, one's middle at `rim_phase` rad in
    #: the item's frame (0 sides: round). The fingers straddle one wall squarely, within
    #: RIM_MAX_SQUINT_RAD of its middle (`tool_yaw`).
    rim_sides: int = 0
    rim_phase: float = 0.0

    def __str__(self) -> str:
        return self.kind

    @property
    def closing_angle(self) -> float:
        return gripper_geometry().closing_angle(self.width_m)

    def tool_yaw(self, item_yaw: float, heading: float) -> float | None:
        """The tool yaw for this grasp of an item turned to `item_yaw`, nearest the robot's
        heading (a front grasp: None if none is within FRONT_MAX_TURN_RAD of it)."""
        if self.yaws is None:
            return self._square_to_a_wall(item_yaw, heading)
        options = [heading + math.remainder(item_yaw + r - heading, 2 * math.pi)
                   for r in self.yaws]
        return self._nearest(options, heading)

    def _square_to_a_wall(self, item_yaw: float, yaw: float) -> float:
        """A rim grasp's tool yaw: `yaw`, turned (the least) so that the fingers cross a
        wall of a rim of flat walls within RIM_MAX_SQUINT_RAD of its middle. Near where two
        walls meet, the fingertips' flat pads would close into the corner they form (the
        bowl's 16 walls: 2 mm deep 8 degrees off a wall's middle, 0.6 mm at it)."""
        if self.kind != "rim" or self.rim_sides < 3:
            return yaw
        # (the tool point lies along the tool's +y: at yaw + 90 deg, in the item's frame)
        off = math.remainder(yaw + math.pi / 2 - item_yaw - self.rim_phase,
                             2 * math.pi / self.rim_sides)
        if abs(off) <= RIM_MAX_SQUINT_RAD:
            return yaw
        return yaw - off + math.copysign(RIM_MAX_SQUINT_RAD, off)

    def place_yaw(self, target_yaw: float, held_yaw: float, heading: float,
                  symmetry_deg: float) -> float | None:
        """The tool yaw that puts an item held with its yaw `held_yaw` off the tool's down
        at `target_yaw` (or a turn of it by its symmetry), nearest the robot's heading
        (None as for `tool_yaw`). An item any turn of which looks the same: the heading."""
        if symmetry_deg <= 0:
            return heading if self.kind != "rim" else heading
        period = math.radians(symmetry_deg)
        turns = max(1, round(2 * math.pi / period))
        options = [heading + math.remainder(target_yaw + k * period - held_yaw - heading,
                                            2 * math.pi) for k in range(turns)]
        return self._nearest(options, heading)

    def _nearest(self, options: Sequence[float], heading: float) -> float | None:
        best = min(options, key=lambda yaw: abs(yaw - heading))
        if self.kind == "front" and abs(best - heading) > FRONT_MAX_TURN_RAD:
            return None
        return best


def item_grasps(model: ItemModel) -> list[Grasp]:
    """The grasps of an item that fit the gripper, in order of preference (the kinds its
    item file allows); raises SetupError naming the item's widths if there is none."""
    out = []
    for kind in model.kind.grasps:
        out += _grasps_of_kind(model, kind)
    if not out:
        ex, ey, ez = model.extents
        opening = gripper_geometry().max_gap
        if _fits(min(ex, ey)):  # (narrow enough: the kinds it allows do not suit its shape)
            raise SetupError(
                f"item type {model.type!r} has no grasp the PR2 gripper can make: it is "
                f"narrow enough ({ex * 100:.1f} x {ey * 100:.1f} cm, height {ez * 100:.1f} "
                f"cm, the gripper fits {(opening - 2 * CLEARANCE_M) * 100:.1f} cm), but "
                f"none of the grasps its item file allows ({', '.join(model.kind.grasps)}) "
                "suits its shape; expected a grasps list that does (see docs/manipulation.md)",
                source=str(model.kind.source or model.urdf), field="grasps")
        raise SetupError(
            f"item type {model.type!r} has no grasp the PR2 gripper can make: its widths are "
            f"{ex * 100:.1f} x {ey * 100:.1f} cm (height {ez * 100:.1f} cm) and it allows "
            f"{', '.join(model.kind.grasps)} grasps; the gripper opens "
            f"{opening * 100:.1f} cm, so it fits {(opening - 2 * CLEARANCE_M) * 100:.1f} cm "
            f"with {CLEARANCE_M * 1000:.0f} mm to spare on each side",
            source=str(model.kind.source or model.urdf), field="grasps")
    return out


def _fits(width: float) -> bool:
    return width <= gripper_geometry().max_gap - 2 * CLEARANCE_M


def _grasps_of_kind(model: ItemModel, kind: str) -> list[Grasp]:
    height = model.extents[2]
    insert = -gripper_geometry().palm_x - PALM_CLEARANCE_M  # how deep into the hand
    if kind == "rim":
        rim = _rim(model)
        if rim is None or not _fits(rim[1]):
            return []
        radius, thickness, top, sides, phase = rim
        return [Grasp("rim", top - RIM_GRIP_M, thickness, None, (0.0, radius), sides, phase)]
    if len(model.shapes) != 1 or model.shapes[0].kind not in (BOX, CYLINDER):
        return []
    shape = model.shapes[0]
    hx, hy = float(shape.half[0]), float(shape.half[1])
    if shape.kind == CYLINDER:
        sides = [(2 * hx, 2 * hx, None)]
    else:  # fingers across x (tool yaw +-90 deg: approach along y), or across y
        sides = [(2 * hx, 2 * hy, (math.pi / 2, -math.pi / 2)), (2 * hy, 2 * hx, (0.0, math.pi))]
    out = []
    for width, depth, yaws in sides:
        if not _fits(width):
            continue
        if kind == "front":
            inset = max(0.0, depth / 2 - insert)
            out.append(Grasp("front", min(height / 2, FRONT_GRASP_MAX_HEIGHT_M), width, yaws,
                             (-inset, 0.0)))
        else:  # (closed, the pads swing out past the tool point: they stay off the floor)
            gripper = gripper_geometry()
            lowest = FINGERTIP_FLOOR_M + max(gripper.front_at(gripper.closing_angle(width)),
                                             gripper.front_at(gripper.upper))
            out.append(Grasp("top", max(height - TOP_GRIP_M, lowest), width, yaws))
    return out


def _rim(model: ItemModel) -> tuple[float, float, float, int, float] | None:
    """(radius, wall thickness, rim height, sides, phase) of a hollow round item made of a
    ring of wall boxes (their local x pointing out from the axis) on a base; None if it is
    not one. `sides`: the number of walls if they are evenly spaced (one's middle at angle
    `phase`), else 0."""
    walls = [s for s in model.shapes if s.kind == BOX and
             np.hypot(*s.in_link[:2, 3]) > 1e-3]
    if len(walls) < 8:
        return None
    radii = [float(np.hypot(*s.in_link[:2, 3])) for s in walls]
    thickness = [2 * float(s.half[0]) for s in walls]
    tops = [float(s.in_link[2, 3] + s.half[2]) for s in walls]
    if max(radii) - min(radii) > 1e-3:
        return None
    angles = sorted(math.atan2(s.in_link[1, 3], s.in_link[0, 3]) for s in walls)
    step = 2 * math.pi / len(walls)
    even = all(abs(math.remainder(a - angles[0] - k * step, 2 * math.pi)) < 1e-3
               for k, a in enumerate(angles))
    return (float(np.mean(radii)), max(thickness), min(tops), len(walls) if even else 0,
            angles[0] if even else 0.0)


def _rz(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


TOOL_DOWN = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # Ry(pi/2)


def tool_pose(grasp: Grasp, bottom_centre: Sequence[float], tool_yaw: float,
              offset_m: float = 0.0, rise_m: float = 0.0) -> pin.SE3:
    """Tool frame in the world for a grasp of an item whose bottom centre is at
    `bottom_centre`, the tool turned to `tool_yaw`; `offset_m` backs off along the
    approach (front) or up (top, rim) for pre-grasp and retreat poses, `rise_m` lifts a
    front one."""
    x, y, z = bottom_centre
    rotation = _rz(tool_yaw)
    dx, dy = grasp.offset
    position = np.array([x, y, z + grasp.height_m]) + rotation @ np.array([dx, dy, 0.0])
    if grasp.kind == "front":
        position -= offset_m * rotation[:, 0]
        position[2] += rise_m
    else:
        rotation = rotation @ TOOL_DOWN
        position[2] += offset_m
    return pin.SE3(rotation, position)


def backed_off(tool: pin.SE3, kind: str, offset_m: float, rise_m: float = 0.0) -> pin.SE3:
    """A tool pose backed off from a grasp (or place) pose: back along the approach and up
    `rise_m` for a front grasp, up `offset_m` for one from above (pre-grasp, retreat)."""
    position = np.array(tool.translation, dtype=float)
    if kind == "front":
        position = position - offset_m * tool.rotation[:, 0]
        position[2] += rise_m
    else:
        position[2] += offset_m
    return pin.SE3(tool.rotation, position)


def in_base_frame(world_pose: pin.SE3, base: tuple[float, float, float]) -> pin.SE3:
    x, y, yaw = base
    return pin.SE3(_rz(yaw), np.array([x, y, 0.0])).actInv(world_pose)


def raised(pose: pin.SE3, dz: float) -> pin.SE3:
    """The same tool pose `dz` metres higher (lifting, or hovering above a place pose)."""
    return pin.SE3(pose.rotation, pose.translation + np.array([0.0, 0.0, dz]))


def relative_pose(tool: pin.SE3, position: Sequence[float],
                  orientation: Sequence[float]) -> tuple[tuple[float, float, float],
                                                         tuple[float, float, float, float]]:
    """An object's pose (position, quaternion x, y, z, w) in the tool frame."""
    x, y, z, w = orientation
    obj = pin.SE3(pin.Quaternion(w, x, y, z).toRotationMatrix(), np.asarray(position, float))
    rel = tool.actInv(obj)
    q = pin.Quaternion(rel.rotation).coeffs()  # x, y, z, w
    return (tuple(map(float, rel.translation)), tuple(map(float, q)))


def tool_for_item(item: pin.SE3, relative: tuple[Sequence[float], Sequence[float]]) -> pin.SE3:
    """The tool pose that holds an item held as `relative` at the item pose `item`."""
    (x, y, z), (qx, qy, qz, qw) = relative
    rel = pin.SE3(pin.Quaternion(qw, qx, qy, qz).toRotationMatrix(), np.array([x, y, z]))
    return item * rel.inverse()


def carry_pose(kind: str, grasp_height: float, arm: str,
               bottom_z: float = CARRY_BOTTOM_Z_M) -> pin.SE3:
    """The tool pose (robot frame) that carries an object grasped with a grasp of `kind`
    (its bottom `bottom_z` high, upright)."""
    side = -1.0 if arm == "right" else 1.0
    rotation = _rz(-side * math.pi / 2) if kind == "front" else TOOL_DOWN
    return pin.SE3(rotation, np.array([CARRY_X_M, side * CARRY_Y_M, bottom_z + grasp_height]))
