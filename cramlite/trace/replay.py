"""Replaying a trace: put a world in each recorded state, to render it or to inspect it.

`render_gif` draws the trace headless (PyBullet's TinyRenderer) at a frame rate of robot
time; `replay_gui` plays it in the PyBullet window; `penetrations` re-checks it, states
and the motion between them, with PyBullet's whole-body queries (independently of the
checker that planned the motions): no robot link inside the kitchen, no held object
inside the kitchen or another item, no robot link inside an item other than the one the
action in progress manipulates.
"""

from __future__ import annotations

import bisect
import math
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from cramlite.errors import UserInputError
from cramlite.trace.format import Trace, TraceError
from cramlite.world.bullet import p
from cramlite.world.setup import load_setup
from cramlite.world.world import World

#: The replay camera: from above the south end, the island on the left, the counter on
#: the right, the robot between them.
CAMERA = {"target": (0.15, 0.15, 0.3), "distance": 5.6, "yaw_deg": -20.0, "pitch_deg": -52.0}
MAX_FRAMES = 20_000


def world_for(trace: Trace, gui: bool = False) -> World:
    """A world of the trace's setup (its header names it as `load_setup` accepts)."""
    try:
        setup = load_setup(trace.header["setup"])
    except UserInputError as exc:
        raise TraceError(f"header field setup: {exc}", field="line 1") from None
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


def frame_count(duration_s: float, fps: float, speed: float) -> int:
    """Frames of a replay: one every `speed / fps` seconds of robot time, both ends in."""
    return int(math.floor(duration_s * fps / speed + 1e-9)) + 1


def states_at_frames(trace: Trace, fps: float, speed: float) -> Iterator[dict[str, Any]]:
    """The state shown in each frame: the last one reached at the frame's robot time."""
    times = [s["t"] for s in trace.states]
    for k in range(frame_count(trace.duration_s, fps, speed)):
        t = k * speed / fps
        yield trace.states[max(0, bisect.bisect_right(times, t + 1e-9) - 1)]


def render_frame(world: World, width: int, height: int) -> np.ndarray:
    from cramlite.world.render import render

    return render(world, width, height, target=CAMERA["target"], distance=CAMERA["distance"],
                  yaw_deg=CAMERA["yaw_deg"], pitch_deg=CAMERA["pitch_deg"], shadow=False)


def caption(image, t: float, state: dict[str, Any]) -> None:
    """Robot time and the action in progress, top left (every frame differs, so a GIF
    writer cannot merge frames)."""
    from PIL import ImageDraw

    action = state.get("action") or {}
    text = f"t = {t:6.2f} s  {action.get('name', '')} {action.get('object') or ''}".rstrip()
    draw = ImageDraw.Draw(image)
    box = draw.textbbox((6, 4), text)
    draw.rectangle((box[0] - 3, box[1] - 2, box[2] + 3, box[3] + 2), fill=(255, 255, 255))
    draw.text((6, 4), text, fill=(0, 0, 0))


def render_gif(trace: Trace, out: str | Path, fps: float = 10.0, speed: float = 1.0,
               width: int = 480, height: int = 360,
               progress: Callable[[int], None] | None = None) -> int:
    """Render the trace as an animated GIF; returns the number of frames."""
    from PIL import Image

    if not trace.states:
        raise TraceError("the trace has no states to replay", field="line 2")
    count = frame_count(trace.duration_s, fps, speed)
    if count > MAX_FRAMES:
        raise UserInputError(f"{count} frames at {fps:g} fps and speed {speed:g}; expected at "
                             f"most {MAX_FRAMES} (raise --speed or lower --fps)",
                             field="--fps")
    frames = []
    joints = trace.header["joints"]
    with world_for(trace) as world:
        for k, state in enumerate(states_at_frames(trace, fps, speed)):
            apply_state(world, joints, state, trace.header["world_joints"])
            image = Image.fromarray(render_frame(world, width, height))
            caption(image, k * speed / fps, state)
            frames.append(image.quantize(colors=128, method=Image.Quantize.MEDIANCUT))
            if progress:
                progress(1)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    frames[0].save(out, save_all=True, append_images=frames[1:], duration=round(1000 / fps),
                   loop=0, optimize=False)
    return len(frames)


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


@dataclass(frozen=True)
class Penetration:
    """The deepest penetration found between two things along a trace."""

    what: str
    other: str
    depth_m: float
    t: float
    line: int  #: the trace line of the state (or the motion that starts there)
    between: bool = False  #: found on the motion from that line's state to the next

    def describe(self) -> str:
        where = f"between lines {self.line} and {self.line + 1}" if self.between \
            else f"line {self.line}"
        return (f"{self.what} {self.depth_m * 100:.1f} cm inside {self.other} at t = "
                f"{self.t:.2f} s ({where})")


def _interpolate(a: dict[str, Any], b: dict[str, Any], s: float) -> dict[str, Any]:
    base = [a["base"][0] + s * (b["base"][0] - a["base"][0]),
            a["base"][1] + s * (b["base"][1] - a["base"][1]),
            a["base"][2] + s * math.remainder(b["base"][2] - a["base"][2], 2 * math.pi)]
    q = [x + s * (y - x) for x, y in zip(a["q"], b["q"], strict=True)]
    w = [x + s * (y - x) for x, y in zip(a["w"], b["w"], strict=True)]
    objects = {}
    for name, pa in a["objects"].items():
        pb = b["objects"].get(name, pa)
        position = [x + s * (y - x) for x, y in zip(pa[:3], pb[:3], strict=True)]
        qa, qb = np.array(pa[3:]), np.array(pb[3:])
        if qa @ qb < 0:
            qb = -qb
        quat = qa + s * (qb - qa)
        objects[name] = [*position, *(quat / np.linalg.norm(quat))]
    return {**a, "t": a["t"] + s * (b["t"] - a["t"]), "base": base, "q": q, "w": w,
            "objects": objects}


def penetrations(trace: Trace, tolerance_m: float = 0.01, substeps: int = 2,
                 world: World | None = None) -> list[Penetration]:
    """Every pair that penetrates deeper than `tolerance_m` somewhere along the trace
    (each state and `substeps - 1` interpolated points between consecutive states),
    with its deepest point; an empty list means nothing was inside anything."""
    own = world is None
    world = world or world_for(trace)
    try:
        return _scan(trace, world, tolerance_m, substeps)
    finally:
        if own:
            world.close()


def _scan(trace: Trace, world: World, tolerance_m: float, substeps: int) -> list[Penetration]:
    joints = trace.header["joints"]
    world_joints = trace.header["world_joints"]
    client, robot, env = world.client, world.robot.body, world.environment
    bodies = {name: obj.body for name, obj in world.objects.items()}
    env_names = {index: name for name, index in world.environment_links.items()}
    link_names = {j: p.getJointInfo(robot, j, physicsClientId=client)[12].decode()
                  for j in range(p.getNumJoints(robot, physicsClientId=client))}
    link_names[-1] = "base"
    worst: dict[tuple[str, str], Penetration] = {}

    def note(what: str, other: str, depth: float, state: dict[str, Any], line: int,
             between: bool) -> None:
        key = (what, other)
        if depth > tolerance_m and (key not in worst or depth > worst[key].depth_m):
            worst[key] = Penetration(what, other, depth, state["t"], line, between)

    def deepest(a: int, b: int) -> dict[tuple[int, int], float]:
        out: dict[tuple[int, int], float] = {}
        for pt in p.getClosestPoints(a, b, 0.0, physicsClientId=client):
            if pt[8] < 0:
                key = (pt[3], pt[4])
                out[key] = max(out.get(key, 0.0), -pt[8])
        return out

    handles = {name: world.environment_links[c.handle] for name, c in world.containers.items()}

    #: where each item not in hand was last checked against the kitchen and the others
    checked_at: dict[str, list[float]] = {}

    def check(state: dict[str, Any], line: int, between: bool = False) -> None:
        apply_state(world, joints, state, world_joints)
        held = set(state["held"])
        action = state.get("action") or {}
        manipulated = action.get("object")
        grasped = handles.get(manipulated)  # opening a container: its handle is in hand

        def found(what: str, other: str, depth: float) -> None:
            note(what, other, depth, state, line, between)

        for (la, lb), depth in deepest(robot, env).items():
            if lb != grasped:
                found(link_names[la], env_names.get(lb, "the kitchen"), depth)
        for name, body in bodies.items():
            if name in held:
                for (_, lb), depth in deepest(body, env).items():
                    found(repr(name), env_names.get(lb, "the kitchen"), depth)
                for other, other_body in bodies.items():
                    if other != name and other != manipulated:
                        for _, depth in deepest(body, other_body).items():
                            found(repr(name), repr(other), depth)
                continue
            if name != manipulated:
                for (la, _), depth in deepest(robot, body).items():
                    found(link_names[la], repr(name), depth)
            # an item standing somewhere (or sliding with a drawer): checked where it moved
            pose = state["objects"].get(name)
            last = checked_at.get(name)
            if pose is None or (last is not None and max(
                    abs(x - y) for x, y in zip(pose, last, strict=True)) < 1e-3):
                continue
            checked_at[name] = list(pose)
            for (_, lb), depth in deepest(body, env).items():
                found(repr(name), env_names.get(lb, "the kitchen"), depth)
            for other, other_body in bodies.items():
                if other != name and other not in held:
                    for _, depth in deepest(body, other_body).items():
                        found(repr(name), repr(other), depth)

    states = trace.states
    for i, state in enumerate(states):
        line = i + 2
        check(state, line)
        if i + 1 < len(states):
            nxt = states[i + 1]
            held_pose = _held_relative(world, joints, world_joints, state)
            for k in range(1, substeps):
                mid = _interpolate(state, nxt, k / substeps)
                _carry_held(world, joints, world_joints, mid, held_pose)
                check(mid, line, between=True)
    return sorted(worst.values(), key=lambda f: -f.depth_m)


def _tool_link(arm: str) -> str:
    return f"{arm[0]}_gripper_tool_frame"


def _held_relative(world: World, joints: Sequence[str], world_joints: Sequence[str],
                   state: dict[str, Any]) -> dict:
    """Held objects' poses in their gripper's frame at a recorded state."""
    apply_state(world, joints, state, world_joints)
    out = {}
    for name, arm in state["held"].items():
        tool = world.robot.link_pose(_tool_link(arm))
        out[name] = (arm, p.multiplyTransforms(*p.invertTransform(*tool),
                                               *world.objects[name].pose()))
    return out


def _carry_held(world: World, joints: Sequence[str], world_joints: Sequence[str],
                state: dict[str, Any], held: dict) -> None:
    """Held objects of an interpolated state follow the interpolated gripper."""
    apply_state(world, joints, state, world_joints)
    for name, (arm, relative) in held.items():
        tool = world.robot.link_pose(_tool_link(arm))
        pos, orn = p.multiplyTransforms(*tool, *relative)
        state["objects"][name] = [*pos, *orn]


__all__ = ["CAMERA", "Penetration", "apply_state", "frame_count", "penetrations",
           "render_gif", "replay_gui", "states_at_frames", "world_for"]
