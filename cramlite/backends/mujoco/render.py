"""Headless images of a `MujocoWorld` with MuJoCo's offscreen renderer.

MuJoCo renders through OpenGL without a display by EGL (the default here, set through
`MUJOCO_GL` unless the user set it) or OSMesa. Where neither works, `GLUnavailable` says
so in one line, and how to get it. Cameras are cramlite's (`cramlite.render.camera`: a
target, distance, yaw and pitch as PyBullet gives them), turned into MuJoCo's
azimuth and elevation.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from cramlite.backends.mujoco.world import MAX_IMAGE, MujocoWorld
from cramlite.errors import UserInputError
from cramlite.render.camera import Camera

GL_HELP = ("MuJoCo's offscreen renderer needs EGL or OSMesa: on Debian or Ubuntu "
           "`apt install libegl1` (or libosmesa6 with MUJOCO_GL=osmesa), and the `pyopengl` "
           "package (pip install 'cramlite[mujoco]')")


class GLUnavailable(UserInputError):
    """No OpenGL context could be made for offscreen rendering."""


class Renderer:
    """An offscreen renderer of one world (its GL context lives as long as this)."""

    def __init__(self, world: MujocoWorld, width: int, height: int):
        if width > MAX_IMAGE[0] or height > MAX_IMAGE[1]:
            raise UserInputError(f"a MuJoCo picture is at most {MAX_IMAGE[0]} x "
                                 f"{MAX_IMAGE[1]} pixels, got {width} x {height}",
                                 field="--size")
        import mujoco

        self.world = world
        self.size = (width, height)
        try:
            self._renderer = mujoco.Renderer(world.model, height, width)
        except Exception as exc:  # (ImportError, RuntimeError, a GL error: all say the same)
            raise GLUnavailable(f"cannot render with MuJoCo (MUJOCO_GL="
                                f"{os.environ.get('MUJOCO_GL')}: {type(exc).__name__}: "
                                f"{str(exc).splitlines()[0] if str(exc) else ''}); "
                                f"{GL_HELP}") from None
        self._camera = mujoco.MjvCamera()
        self._options = mujoco.MjvOption()
        self._options.geomgroup[:] = 0
        self._options.geomgroup[1] = 1  # the visual meshes, not the collision hulls

    def image(self, view: Camera) -> np.ndarray:
        """An RGB image (height x width x 3, uint8) from the camera."""
        import mujoco

        self.world.forward()
        cam = self._camera
        cam.type = mujoco.mjtCamera.mjCAMERA_FREE
        cam.lookat[:] = view.target
        cam.distance = view.distance
        cam.azimuth = view.yaw_deg + 90.0  # (PyBullet's yaw 0 looks along +y; MuJoCo's +x)
        cam.elevation = view.pitch_deg
        self._renderer.update_scene(self.world.data, camera=cam, scene_option=self._options)
        return np.array(self._renderer.render(), dtype=np.uint8)

    def close(self) -> None:
        self._renderer.close()

    def __enter__(self) -> Renderer:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def render(world: MujocoWorld, width: int, height: int, view: Camera) -> np.ndarray:
    """One picture (a renderer made and closed for it)."""
    with Renderer(world, width, height) as renderer:
        return renderer.image(view)
