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


def gl_help() -> str:
    """What to do, for the OpenGL platform asked for (MUJOCO_GL)."""
    asked = os.environ.get("MUJOCO_GL", "")
    if asked == "glfw" and not os.environ.get("DISPLAY"):
        return "glfw needs a display and DISPLAY is not set: unset MUJOCO_GL (EGL) instead"
    if asked == "osmesa":
        return ("OSMesa needs libOSMesa: on Debian or Ubuntu `apt install libosmesa6`, or "
                "unset MUJOCO_GL (EGL)")
    return GL_HELP


class GLUnavailable(UserInputError):
    """No OpenGL context could be made for offscreen rendering."""


class Renderer:
    """An offscreen renderer of one world (its GL context lives as long as this)."""

    def __init__(self, world: MujocoWorld, width: int, height: int):
        import warnings

        import mujoco

        from cramlite.backends.mujoco import GL_IMPORT_ERROR

        self.world = world
        self.size = (width, height)
        # (the offscreen buffer is made as large as the model says: this picture's size)
        visual = world.model.vis.global_
        visual.offwidth, visual.offheight = max(width, MAX_IMAGE[0]), max(height, MAX_IMAGE[1])
        try:
            with warnings.catch_warnings():  # (glfw warns before it fails: said below)
                warnings.simplefilter("ignore")
                self._renderer = mujoco.Renderer(world.model, height, width)
        except Exception as exc:  # (ImportError, RuntimeError, a GL error: all say the same)
            reason = GL_IMPORT_ERROR or (f"{type(exc).__name__}: "
                                         f"{str(exc).splitlines()[0] if str(exc) else ''}")
            raise GLUnavailable(f"cannot render with MuJoCo (MUJOCO_GL="
                                f"{os.environ.get('MUJOCO_GL')}: {reason}); "
                                f"{gl_help()}") from None
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
