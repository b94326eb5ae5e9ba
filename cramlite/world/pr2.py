"""The PR2 from example-robot-data: where its files are, and the poses cramlite uses.

Simulators cannot resolve `package://` mesh paths of a URDF loaded from elsewhere, so
the installed URDF is copied once with the prefix replaced by the real share folder
(found through `example_robot_data.getModelPath`); Pinocchio reads the original with the
share folder as its package directory (`cramlite.scene.models`).
"""

from __future__ import annotations

import functools
import hashlib
import os
import tempfile
from pathlib import Path

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
#: What one PR2 hand may hold (kg): the PR2's rated payload per arm (Willow Garage's
#: specification, 1.8 kg). With two items carried each is held by its own hand.
HAND_PAYLOAD_KG = 1.8
#: How far the tool frame (between the fingertips) may be from an object's bounds for
#: the gripper to hold it (its fingers are 4 cm long).
ATTACH_REACH_M = 0.03
