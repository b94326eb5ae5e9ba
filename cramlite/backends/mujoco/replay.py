"""MuJoCo's part of replaying a trace: a world of the trace's setup, put in each recorded
state (to render it)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from cramlite.backends.mujoco.world import MujocoWorld
from cramlite.trace.format import Trace, TraceError, trace_setup


def world_for(trace: Trace) -> MujocoWorld:
    """A world of the trace's setup (its header names it as `load_setup` accepts)."""
    setup = trace_setup(trace)
    world = MujocoWorld(setup)
    missing = [n for n in trace.header["joints"] if n not in world.robot_qpos]
    missing += [n for n in trace.header["world_joints"] if n not in world.world_qpos]
    if missing:
        raise TraceError(f"header fields joints/world_joints: no joint {missing[0]!r} in the "
                         "robot or the world", field="line 1")
    return world


def apply_state(world: MujocoWorld, joints: Sequence[str], state: dict[str, Any],
                world_joints: Sequence[str] = ()) -> None:
    """Put the robot, the drawers and doors, and the objects where the state says."""
    world.set_base_pose(*state["base"])
    world.set_joint_positions(dict(zip(joints, state["q"], strict=True)))
    for name, value in zip(world_joints, state["w"], strict=True):
        world.data.qpos[world.world_qpos[name]] = value
    for name, pose in state["objects"].items():
        if name in world.item_qpos:
            world.set_object_pose(name, tuple(pose[:3]), tuple(pose[3:]))
    world.forward()
