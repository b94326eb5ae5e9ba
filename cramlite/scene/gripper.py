"""The PR2 gripper's geometry, measured on its model: how wide the fingers open at each
finger angle, where the finger pads are, how deep an item reaches into the hand.

Measured in the tool frame (`*_gripper_tool_frame`: x along the fingers, out of the hand;
y the direction the fingers close along; z across them), with the six finger joints of a
gripper moving together as the URDF's mimic tags say. The gap is the distance between the
two fingertip pads' inner surfaces (8.5 cm at 0.5 rad, 9.2 cm at the limit, 0.548 rad);
it is worked out for a range of angles once per process and inverted by interpolation.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from cramlite.scene.models import pr2_model

#: The finger joint every other finger joint of a gripper follows.
LEADER = "gripper_l_finger_joint"
TIPS = ("gripper_l_finger_tip_link", "gripper_r_finger_tip_link")
HAND = ("gripper_palm_link", "gripper_l_finger_link", "gripper_r_finger_link", *TIPS)
#: The fingers close this much past first contact (the pads press 0.5 mm into what they
#: hold on each side: held, not magnetised).
SQUEEZE_M = 0.001


@dataclass(frozen=True)
class GripperGeometry:
    """See the module's doc."""

    angles: np.ndarray  #: finger angles (leader joint, rad), ascending
    gaps: np.ndarray  #: the pads' gap at each (m), ascending
    #: How far the pads reach along the tool's x at each angle (closing swings them out)
    fronts: np.ndarray
    upper: float  #: the finger joint's upper limit (rad)
    pad_x: tuple[float, float]  #: the pads' extent along the tool's x (m)
    pad_half_z: float  #: the pads' half extent across the fingers (tool z)
    #: The tool x of the front of the palm: an item may reach this far into the hand.
    palm_x: float

    @property
    def max_gap(self) -> float:
        return float(self.gaps[-1])

    def angle_for_gap(self, gap: float) -> float:
        """The finger angle at which the pads are `gap` apart (clipped to the range)."""
        return float(np.interp(gap, self.gaps, self.angles))

    def gap_at(self, angle: float) -> float:
        return float(np.interp(angle, self.angles, self.gaps))

    def front_at(self, angle: float) -> float:
        """How far along the tool's x the pads reach at a finger angle."""
        return float(np.interp(angle, self.angles, self.fronts))

    def closing_angle(self, width: float) -> float:
        """Where the fingers stop on something `width` across: at contact, pressing
        SQUEEZE_M in."""
        return self.angle_for_gap(max(0.0, width - SQUEEZE_M))


@functools.cache
def gripper_geometry() -> GripperGeometry:
    """The right gripper's geometry (the left one is its mirror image)."""
    robot = pr2_model()
    prefix = "r_"
    leader = prefix + LEADER
    info = robot.joints[leader]
    angles = np.linspace(0.0, info.upper, 23)
    gaps, pads, palms = [], [], []
    tool = prefix + "gripper_tool_frame"
    links = [prefix + name for name in HAND]
    # (the meshes' vertices: a coordinate's extremes over a triangle lie at its corners)
    for angle in angles:
        frames = robot.link_placements(robot.with_mimics({leader: float(angle)}),
                                       [tool, *links])
        to_tool = np.linalg.inv(frames[tool])
        points = {}
        for link in links:
            out = []
            for shape in robot.shapes_by_link.get(link, []):
                if shape.vertices is None:
                    continue
                placed = to_tool @ frames[link] @ shape.in_link
                out.append(shape.vertices @ placed[:3, :3].T + placed[:3, 3])
            points[link] = np.vstack(out)
        left, right = points[prefix + TIPS[0]], points[prefix + TIPS[1]]
        gaps.append(float(left[:, 1].min() - right[:, 1].max()))
        pads.append((min(left[:, 0].min(), right[:, 0].min()),
                     max(left[:, 0].max(), right[:, 0].max()),
                     float(np.abs(left[:, 2]).max())))
        palms.append(float(points[prefix + HAND[0]][:, 0].max()))
    gaps_arr = np.maximum.accumulate(np.maximum(np.array(gaps), 0.0))
    widest = pads[-1]
    fronts = np.array([pad[1] for pad in pads])
    return GripperGeometry(angles, gaps_arr, fronts, float(info.upper),
                           (widest[0], widest[1]), widest[2], max(palms))
