"""Replaying a trace: the frames of an animation at a frame rate of robot time.

`render_gif` draws the trace headless: each frame shows the state reached at its robot
time, drawn by the renderer of a backend (`cramlite.render`: PyBullet's TinyRenderer for
pybullet, cramlite's own rasteriser for the others); `replay_gui` plays it in the PyBullet
window. The check of a trace (`replay --check`) is `cramlite.trace.check`.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from cramlite.errors import UserInputError
from cramlite.trace.check import Penetration, penetrations
from cramlite.trace.format import Trace, TraceError

MAX_FRAMES = 20_000


def frame_count(duration_s: float, fps: float, speed: float) -> int:
    """Frames of a replay: one every `speed / fps` seconds of robot time, both ends in."""
    return int(math.floor(duration_s * fps / speed + 1e-9)) + 1


def states_at_frames(trace: Trace, fps: float, speed: float) -> Iterator[dict[str, Any]]:
    """The state shown in each frame: the last one reached at the frame's robot time."""
    times = [s["t"] for s in trace.states]
    for k in range(frame_count(trace.duration_s, fps, speed)):
        t = k * speed / fps
        yield trace.states[max(0, bisect.bisect_right(times, t + 1e-9) - 1)]


#: What the robot is doing, by action, in the captions (the object follows the verb).
DOING = {"NavigateAction": "driving", "PickUpAction": "picking up", "PlaceAction":
         "putting down", "OpenAction": "opening", "CloseAction": "closing",
         "ParkArmsAction": "parking the arms", "MoveTorsoAction": "moving the torso",
         "LookAtAction": "looking at", "DetectAction": "looking for", "SetGripperAction":
         "moving a gripper", "TransportAction": "fetching", "FetchAction": "fetching",
         "DeliverAction": "delivering", "PickAndPlaceAction":
         "moving"}


def doing(state: dict[str, Any]) -> str:
    """The caption's words for a state: what the robot does and what it carries, e.g.
    "carrying bowl (right hand): parking the arms", "opening drawer_1"."""
    action = state.get("action") or {}
    name = action.get("name") or ""
    obj = action.get("object") or ""
    held = state.get("held") or {}
    verb = DOING.get(name, name.removesuffix("Action").lower())
    if obj and obj in held and name not in ("PickUpAction", "PlaceAction"):
        obj = ""  # (it is the one carried: said below)
    words = f"{verb} {obj}".strip()
    if held:
        carried = ", ".join(f"{item} ({arm} hand)" for item, arm in sorted(held.items()))
        return f"carrying {carried}: {words}" if words else f"carrying {carried}"
    return words


def caption(image, t: float, state: dict[str, Any]) -> None:
    """Robot time and what the robot does, top left (every frame differs, so a GIF
    writer cannot merge frames)."""
    from PIL import ImageDraw

    text = f"t = {t:6.2f} s  {doing(state)}".rstrip()
    draw = ImageDraw.Draw(image)
    box = draw.textbbox((6, 4), text)
    draw.rectangle((box[0] - 3, box[1] - 2, box[2] + 3, box[3] + 2), fill=(255, 255, 255))
    draw.text((6, 4), text, fill=(0, 0, 0))


def render_gif(trace: Trace, out: str | Path, fps: float = 10.0, speed: float = 1.0,
               width: int = 480, height: int = 360,
               progress: Callable[[int], None] | None = None,
               backend: str | None = None, camera: str = "fixed") -> int:
    """Render the trace as an animated GIF (drawn as `backend` draws: default the
    default backend; `camera`: fixed, top or follow, see `replay_view`); returns the
    number of frames."""
    from PIL import Image

    from cramlite.backends import default_backend
    from cramlite.render import TraceFrames
    from cramlite.render.camera import replay_view

    replay_view(camera, (0.0, 0.0, 0.0))  # (an unknown mode fails before any drawing)

    if not trace.states:
        raise TraceError("the trace has no states to replay", field="line 2")
    count = frame_count(trace.duration_s, fps, speed)
    if count > MAX_FRAMES:
        raise UserInputError(f"{count} frames at {fps:g} fps and speed {speed:g}; expected at "
                             f"most {MAX_FRAMES} (raise --speed or lower --fps)",
                             field="--fps")
    frames = []
    with TraceFrames(trace, backend or default_backend()) as drawer:
        for k, state in enumerate(states_at_frames(trace, fps, speed)):
            image = Image.fromarray(drawer.image(state, width, height,
                                                 replay_view(camera, state["base"])))
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
    from cramlite.backends.pybullet.replay import replay_gui as play

    play(trace, speed)


__all__ = ["DOING", "MAX_FRAMES", "Penetration", "caption", "doing", "frame_count",
           "penetrations", "render_gif", "replay_gui", "states_at_frames"]
