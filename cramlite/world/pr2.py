"""The PR2 from example-robot-data, for PyBullet and for Pinocchio from one URDF.

PyBullet cannot resolve `package://` mesh paths of a URDF loaded from elsewhere, so the
installed URDF is copied once with the prefix replaced by the real share folder (found
through `example_robot_data.getModelPath`). Pinocchio builds its model from the same
file once per process; joint orders differ between the two, so they are mapped by name.
"""

from __future__ import annotations

import functools
import hashlib
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

PR2_URDF_SUBPATH = "pr2_description/urdf/pr2.urdf"
PACKAGE_PREFIX = "package://example-robot-data/robots/"

#: Footprint of the PR2 base (square, metres), used by base planning and placement.
PR2_BASE_HALF_SIZE_M = 0.337
#: Torso joint and its range (metres).
TORSO_JOINT = "torso_lift_joint"


@functools.cache
def pr2_share_folder() -> Path:
    """The installed `robots` folder of example-robot-data that holds pr2_description."""
    import example_robot_data

    return Path(os.path.realpath(example_robot_data.getModelPath(PR2_URDF_SUBPATH)))


@functools.cache
def pr2_urdf_path() -> Path:
    """A copy of the PR2 URDF whose mesh paths are absolute (written once, reused)."""
    share = pr2_share_folder()
    original = share / PR2_URDF_SUBPATH
    text = original.read_text().replace(PACKAGE_PREFIX, f"{share}/")
    digest = hashlib.sha1(text.encode()).hexdigest()[:12]
    target = Path(tempfile.gettempdir()) / f"cramlite-pr2-{digest}.urdf"
    if not target.exists():
        fd, tmp = tempfile.mkstemp(suffix=".urdf", dir=target.parent)
        with os.fdopen(fd, "w") as handle:
            handle.write(text)
        os.replace(tmp, target)
    return target


@dataclass(frozen=True)
class PinocchioPR2:
    """The PR2's Pinocchio model (fixed base: base_footprint is the root frame)."""

    model: object  # pinocchio.Model

    @property
    def joint_names(self) -> tuple[str, ...]:
        m = self.model
        return tuple(m.names[i] for i in range(1, m.njoints))

    def q_index(self, joint_name: str) -> int:
        """Index of a joint's first configuration value in q."""
        m = self.model
        return int(m.idx_qs[m.getJointId(joint_name)])

    def is_continuous(self, joint_name: str) -> bool:
        m = self.model
        return int(m.nqs[m.getJointId(joint_name)]) == 2


@functools.cache
def pinocchio_pr2() -> PinocchioPR2:
    """Build the Pinocchio model of the PR2 once per process (fixed base, like PyBullet)."""
    import pinocchio as pin

    model = pin.buildModelFromUrdf(str(pr2_urdf_path()))
    return PinocchioPR2(model=model)


@dataclass(frozen=True)
class JointMap:
    """Maps joints by name between a PyBullet body and the Pinocchio model.

    PyBullet numbers every URDF joint (fixed ones too); Pinocchio keeps only moving
    joints, and represents a continuous joint as a (cos, sin) pair.
    """

    bullet_index: dict[str, int]
    pin_model: PinocchioPR2

    def bullet_to_q(self, bullet_positions: dict[str, float]) -> np.ndarray:
        """A Pinocchio configuration from joint angles by name (missing joints: neutral)."""
        import pinocchio as pin

        q = pin.neutral(self.pin_model.model)
        for name, value in bullet_positions.items():
            if name not in self.bullet_index or name not in self.pin_model.joint_names:
                continue
            i = self.pin_model.q_index(name)
            if self.pin_model.is_continuous(name):
                q[i], q[i + 1] = np.cos(value), np.sin(value)
            else:
                q[i] = value
        return q

    def q_to_bullet(self, q: np.ndarray) -> dict[str, float]:
        """Joint angles by name from a Pinocchio configuration (continuous joints via atan2)."""
        out: dict[str, float] = {}
        for name in self.pin_model.joint_names:
            if name not in self.bullet_index:
                continue
            i = self.pin_model.q_index(name)
            if self.pin_model.is_continuous(name):
                out[name] = float(np.arctan2(q[i + 1], q[i]))
            else:
                out[name] = float(q[i])
        return out


#: Arms tucked for driving (PyCRAM's PR2 park pose), by arm.
PARK_JOINTS: dict[str, dict[str, float]] = {
    "right": {"r_shoulder_pan_joint": -1.712, "r_shoulder_lift_joint": -0.256,
              "r_upper_arm_roll_joint": -1.463, "r_elbow_flex_joint": -2.12,
              "r_forearm_roll_joint": 1.766, "r_wrist_flex_joint": -0.07,
              "r_wrist_roll_joint": 0.051},
    "left": {"l_shoulder_pan_joint": 1.712, "l_shoulder_lift_joint": -0.264,
             "l_upper_arm_roll_joint": 1.38, "l_elbow_flex_joint": -2.12,
             "l_forearm_roll_joint": 0.41, "l_wrist_flex_joint": -0.073,
             "l_wrist_roll_joint": 0.0},
}
#: Torso height for table setting (metres; the joint's range is 0 to 0.31).
TORSO_UP_M = 0.25
