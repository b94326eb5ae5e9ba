"""PyBullet's part of replaying a trace: a world of the trace's setup, put in each
recorded state (to render it, or to play it in the GUI)."""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from cramlite.backends.pybullet.client import p
from cramlite.backends.pybullet.world import World
from cramlite.trace.format import Trace, TraceError, trace_setup

#: The replay camera: from above the south end, the island on the left, the counter on
#: the right, the robot between them.
CAMERA = {"target": (0.15, 0.15, 0.3), "distance": 5.6, "yaw_deg": -20.0, "pitch_deg": -52.0}


def world_for(trace: Trace, gui: bool = False) -> World:
    """A world of the trace's setup (its header names it as `load_setup` accepts)."""
    setup = trace_setup(trace)
    world = World.from_setup(setup, gui=gui)
    missing = [n for n in trace.header["joints"] if n not in world.robot.joint_index]
    missing += [n for n in trace.header["world_joints"] if n not in world.world_joints]
    if missing:
        world.close()
        raise TraceError(f"header fields joints/world_joints: no joint {missing[0]!r} in the "
                         "robot or the world", field="line 1")
    return world


def apply_state(world: World, joints: Sequence[str], state: dict[str, Any],
                world_joints: Sequence[str] = ()) -> None:
    """Put the robot, the drawers and doors, and the objects where the state says."""
    world.robot.set_base_pose(*state["base"])
    world.robot.set_joint_positions(dict(zip(joints, state["q"], strict=True)))
    everything = set(world.objects)
    for name, value in zip(world_joints, state["w"], strict=True):
        world.set_world_joint(name, value, exclude=everything)
    for name, pose in state["objects"].items():
        if name in world.objects:
            world.objects[name].set_pose(tuple(pose[:3]), tuple(pose[3:]))


def render_frame(world: World, width: int, height: int, view: dict | None = None,
                 ) -> np.ndarray:
    from cramlite.backends.pybullet.render import render

    view = {**CAMERA, **(view or {})}
    return render(world, width, height, target=view["target"], distance=view["distance"],
                  yaw_deg=view["yaw_deg"], pitch_deg=view["pitch_deg"], shadow=False)


def replay_gui(trace: Trace, speed: float = 1.0) -> None:
    """Play the trace in the PyBullet window in (scaled) real time."""
    joints = trace.header["joints"]
    with world_for(trace, gui=True) as world:
        p.resetDebugVisualizerCamera(CAMERA["distance"], CAMERA["yaw_deg"], CAMERA["pitch_deg"],
                                     CAMERA["target"], physicsClientId=world.client)
        start = time.perf_counter()
        for state in trace.states:
            delay = state["t"] / speed - (time.perf_counter() - start)
            if delay > 0:
                time.sleep(delay)
            apply_state(world, joints, state, trace.header["world_joints"])
