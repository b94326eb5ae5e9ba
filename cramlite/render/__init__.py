"""Pictures of setups and of traced states, headless.

Three renderers draw the same scenes from the same cameras: PyBullet's TinyRenderer (the
pybullet backend's, where pybullet is installed), MuJoCo's offscreen OpenGL renderer (the
mujoco backend's: EGL or OSMesa) and cramlite's own rasteriser of the planning scene's
shapes (`cramlite.render.raster`: numpy and Pillow only, so pictures, replays and the
report's animations work on any Python, with no simulator and no OpenGL). A picture is
drawn by the renderer of the backend asked for: `pybullet` with TinyRenderer, `mujoco`
with MuJoCo's, every other backend with cramlite's own.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from cramlite.render.camera import REPLAY_CAMERA, SHOW_CAMERA, Camera, camera
from cramlite.world.setup import Setup


def uses_pybullet(backend: str) -> bool:
    return backend == "pybullet"


def uses_mujoco(backend: str) -> bool:
    return backend == "mujoco"


def draw_setup(setup: Setup, width: int, height: int, backend: str) -> np.ndarray:
    """A labelled picture of a setup at its start (see `cramlite show`)."""
    if uses_pybullet(backend):
        from cramlite.backends.pybullet.render import render_labelled
        from cramlite.backends.pybullet.world import World

        with World.from_setup(setup) as world:
            return render_labelled(world, width, height)
    if uses_mujoco(backend):
        from cramlite.backends.mujoco.render import render
        from cramlite.backends.mujoco.world import MujocoWorld
        from cramlite.render.labels import label_setup

        view = camera(SHOW_CAMERA, SHOW_CAMERA)
        with MujocoWorld(setup) as world:
            image = render(world, width, height, view)
            positions = {name: world.object_pose(name)[0] for name in world.item_qpos}
        return label_setup(image, setup, positions,
                           lambda points: view.project(points, width, height))
    from cramlite.render.labels import label_setup
    from cramlite.scene.scene import PlanningScene

    scene = PlanningScene(setup)
    view = camera(SHOW_CAMERA, SHOW_CAMERA)
    image = scene_image(scene, width, height, view)
    positions = {name: scene.object_pose(name)[0] for name in scene.items}
    return label_setup(image, setup, positions, lambda points: view.project(points, width,
                                                                            height))


def scene_image(scene, width: int, height: int, view: Camera) -> np.ndarray:
    """cramlite's own picture of a planning scene as it is believed to be."""
    from cramlite.render.draw import scene_triangles
    from cramlite.render.raster import rasterise

    triangles, colours = scene_triangles(scene)
    return rasterise(triangles, colours, view, width, height)


class TraceFrames:
    """Draws the states of a trace (one renderer, one world or scene of its setup)."""

    def __init__(self, trace, backend: str):
        self.trace = trace
        self.backend = backend
        self._world: Any = None
        self._mujoco: Any = None  # (a MuJoCo world and its renderer)
        self._scene: Any = None

    def __enter__(self) -> TraceFrames:
        if uses_pybullet(self.backend):
            from cramlite.backends.pybullet.replay import world_for

            self._world = world_for(self.trace)
        elif uses_mujoco(self.backend):
            from cramlite.backends.mujoco.replay import world_for as mujoco_world_for

            self._mujoco = [mujoco_world_for(self.trace), None]
        else:
            from cramlite.scene.scene import PlanningScene
            from cramlite.trace.check import checker_for

            checker_for(self.trace)  # (the header names a loadable setup and its joints)
            self._scene = PlanningScene(_setup(self.trace))
        return self

    def __exit__(self, *exc: Any) -> None:
        if self._world is not None:
            self._world.close()
        if self._mujoco is not None and self._mujoco[1] is not None:
            self._mujoco[1].close()

    def image(self, state: dict[str, Any], width: int, height: int,
              view: dict | None = None) -> np.ndarray:
        header = self.trace.header
        if self._world is not None:
            from cramlite.backends.pybullet.replay import apply_state, render_frame

            apply_state(self._world, header["joints"], state, header["world_joints"])
            return render_frame(self._world, width, height, view)
        if self._mujoco is not None:
            from cramlite.backends.mujoco.render import Renderer
            from cramlite.backends.mujoco.replay import apply_state as mujoco_apply

            world, renderer = self._mujoco
            if renderer is None or renderer.size != (width, height):
                if renderer is not None:
                    renderer.close()
                renderer = self._mujoco[1] = Renderer(world, width, height)
            mujoco_apply(world, header["joints"], state, header["world_joints"])
            return renderer.image(camera(view or REPLAY_CAMERA, REPLAY_CAMERA))
        scene = self._scene
        belief = scene.belief
        belief.base = tuple(state["base"])
        belief.joints.update(dict(zip(header["joints"], state["q"], strict=True)))
        belief.world_joints.update(dict(zip(header["world_joints"], state["w"], strict=True)))
        belief.poses.update({name: (tuple(pose[:3]), tuple(pose[3:]))
                             for name, pose in state["objects"].items() if name in scene.items})
        return scene_image(scene, width, height, camera(view or REPLAY_CAMERA, REPLAY_CAMERA))

    def frames(self, states: Iterator[dict[str, Any]], width: int, height: int,
               ) -> Iterator[np.ndarray]:
        for state in states:
            yield self.image(state, width, height)


def _setup(trace) -> Setup:
    from cramlite.trace.format import trace_setup

    return trace_setup(trace)


def save_image(image: np.ndarray, path: str | Path) -> Path:
    from PIL import Image

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(image).save(path)
    return path


__all__ = ["REPLAY_CAMERA", "SHOW_CAMERA", "TraceFrames", "draw_setup", "save_image",
           "scene_image", "uses_mujoco", "uses_pybullet"]
