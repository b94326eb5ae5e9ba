"""The MuJoCo backend's `MujocoWorld`: one MjModel and MjData with the kitchen, the PR2 and
the items of a setup, composed with MjSpec from the same URDFs the other backends load.

What MuJoCo's URDF import needed (mujoco-core 4.0.1, the example-robot-data PR2):
- absolute mesh paths (`cramlite.world.pr2.pr2_urdf_path` already writes them: MuJoCo turns
  `package://` into a broken `package:/...` path);
- a `<mujoco><compiler .../></mujoco>` element in each URDF: `balanceinertia` (the PR2's
  inertias fail MuJoCo's triangle-inequality check otherwise), `fusestatic="false"` (else
  83 bodies are fused into 31 and the tool frames vanish), `discardvisual="false"` (the
  visual meshes draw the pictures: group 1; the collision geoms are group 0);
- the PR2's root (`base_footprint`, which the import welds to the world) made a mocap body:
  the base moves as the other backends move it, by setting its pose;
- every item's body given a free joint (the import welds single links to the world).
The 10 mimic tags become joint-equality constraints; mesh collision uses convex hulls.

The robot moves kinematically (its geoms collide with nothing: contype 0, as the robot
in the pybullet backend), the kitchen's geoms collide with items only, items with the
kitchen and each other. Each world owns its model and data; nothing is kept at module level.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from cramlite.errors import SetupError
from cramlite.scene.transforms import Pose, Quat, Vec3, matrix_pose, pose_matrix, yaw_quat
from cramlite.world.containers import Container, load_containers
from cramlite.world.pr2 import pr2_urdf_path
from cramlite.world.setup import Setup

TIME_STEP_S = 0.002
#: Joint damping (N s/m or N m s/rad) of the robot's and the kitchen's joints: physics
#: steps (settling) must not move them (MuJoCo integrates damping implicitly: stable).
HOLD_DAMPING = 1e5
#: Collision bits: the kitchen collides with items, items with the kitchen and items, the
#: robot with nothing (it moves kinematically; held items are carried with the gripper).
KITCHEN_BITS = (2, 1)  # (contype, conaffinity)
ITEM_BITS = (1, 3)
ROBOT_PREFIX = "pr2/"
ITEM_PREFIX = "item/"
#: The largest picture the offscreen renderer is sized for.
MAX_IMAGE = (1920, 1440)

_COMPILER = ('<mujoco><compiler balanceinertia="true" discardvisual="false" '
             'fusestatic="false" strippath="false"/></mujoco>')


def urdf_spec(path: Path) -> mujoco.MjSpec:
    """A URDF read as an MjSpec, with the compiler settings above."""
    try:
        text = Path(path).read_text()
    except OSError as exc:
        raise SetupError(f"cannot read the URDF ({exc.strerror})", source=str(path)) from None
    text, found = re.subn(r"(<robot\b[^>]*>)", r"\1" + _COMPILER, text, count=1)
    if not found:
        raise SetupError("expected a <robot> element", source=str(path))
    try:
        return mujoco.MjSpec.from_string(text)
    except ValueError as exc:
        raise SetupError(f"MuJoCo could not read this URDF: {exc}", source=str(path)) from None


def _set_bits(spec: mujoco.MjSpec, bits: tuple[int, int], damping: float | None = None) -> None:
    for geom in spec.geoms:
        if geom.group == 0:  # (collision geoms; visual ones, group 1, collide with nothing)
            geom.contype, geom.conaffinity = bits
        else:
            geom.contype = geom.conaffinity = 0
    if damping is not None:
        for joint in spec.joints:
            try:
                joint.damping = [damping, 0.0, 0.0]  # (mujoco 4: a polynomial's terms)
            except TypeError:
                joint.damping = damping  # (mujoco 3)


def _wxyz(q: Quat) -> list[float]:
    return [q[3], q[0], q[1], q[2]]


def _xyzw(q: Any) -> Quat:
    return (float(q[1]), float(q[2]), float(q[3]), float(q[0]))


@dataclass(frozen=True)
class Snapshot:
    """Everything a plan changes (qpos, mocap), to reset a world cheaply between trials."""

    qpos: np.ndarray
    mocap_pos: np.ndarray
    mocap_quat: np.ndarray


class MujocoWorld:
    """A MuJoCo world of a setup. Use as a context manager or call `close()`."""

    def __init__(self, setup: Setup):
        self.setup = setup
        world = urdf_spec(setup.world_urdf)
        _set_bits(world, KITCHEN_BITS, HOLD_DAMPING)
        world.option.timestep = TIME_STEP_S
        world.visual.global_.offwidth, world.visual.global_.offheight = MAX_IMAGE
        world.visual.global_.fovy = 50.0  # (the field of view of cramlite's cameras)
        world.visual.headlight.ambient = [0.45, 0.45, 0.45]
        world.visual.headlight.diffuse = [0.5, 0.5, 0.5]
        world.worldbody.add_light(pos=[0.0, 0.0, 6.0], dir=[0.3, -0.4, -1.0],
                                  diffuse=[0.6, 0.6, 0.6], castshadow=False)
        environment = world.worldbody.first_body()
        self.environment_root = environment.name if environment is not None else ""
        robot = urdf_spec(pr2_urdf_path())
        _set_bits(robot, (0, 0), HOLD_DAMPING)
        for body in robot.bodies:
            body.gravcomp = 1.0
        root = robot.worldbody.first_body()
        root.mocap = True
        self.robot_root = ROBOT_PREFIX + root.name
        world.attach(robot, prefix=ROBOT_PREFIX, frame=world.worldbody.add_frame())
        self.item_body: dict[str, str] = {}
        for i, item in enumerate(setup.items):
            spec = urdf_spec(item.urdf)
            _set_bits(spec, ITEM_BITS)
            body = spec.worldbody.first_body()
            if body is None:
                raise SetupError("expected a link", source=str(item.urdf),
                                 field=f"items[{i}].type")
            body.add_freejoint()
            prefix = f"{ITEM_PREFIX}{item.name}/"
            self.item_body[item.name] = prefix + body.name
            world.attach(spec, prefix=prefix, frame=world.worldbody.add_frame())
        try:
            self.model = world.compile()
        except ValueError as exc:
            raise SetupError(f"MuJoCo could not compile the world: {exc}",
                             source=str(setup.source)) from None
        self.data = mujoco.MjData(self.model)
        self._index()
        self.containers: dict[str, Container] = {
            name: c for name, c in load_containers(setup.world_urdf).items()
            if c.inside_link in self._bodies}
        self.set_base_pose(setup.robot_start.x, setup.robot_start.y, setup.robot_start.yaw)
        for item in setup.items:
            self.set_object_pose(item.name, item.pose.xyz, yaw_quat(item.pose.yaw))
        self.forward()

    def _index(self) -> None:
        m = self.model
        names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) or "" for j in range(m.njnt)]
        #: qpos address of every hinge and slide joint: the robot's (by URDF name) ...
        self.robot_qpos = {n[len(ROBOT_PREFIX):]: int(m.jnt_qposadr[j])
                           for j, n in enumerate(names) if n.startswith(ROBOT_PREFIX)}
        #: ... and the kitchen's drawers and doors
        self.world_qpos = {n: int(m.jnt_qposadr[j]) for j, n in enumerate(names)
                           if n and not n.startswith((ROBOT_PREFIX, ITEM_PREFIX))
                           and m.jnt_type[j] != mujoco.mjtJoint.mjJNT_FREE}
        self.world_dof = {n: int(m.jnt_dofadr[m.joint(n).id]) for n in self.world_qpos}
        self.robot_dof = [int(m.jnt_dofadr[m.joint(ROBOT_PREFIX + n).id])
                          for n in self.robot_qpos]
        self._bodies = {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b): b
                        for b in range(m.nbody)}
        self.item_qpos: dict[str, int] = {}
        self.item_dof: dict[str, int] = {}
        for name, body in self.item_body.items():
            joint = int(m.body_jntadr[self._bodies[body]])
            self.item_qpos[name] = int(m.jnt_qposadr[joint])
            self.item_dof[name] = int(m.jnt_dofadr[joint])
        self.mocap = int(m.body_mocapid[self._bodies[self.robot_root]])
        self.robot_limits = {n: (float(m.jnt_range[m.joint(ROBOT_PREFIX + n).id][0]),
                                 float(m.jnt_range[m.joint(ROBOT_PREFIX + n).id][1]))
                             for n in self.robot_qpos}

    # -- lifetime -------------------------------------------------------------------
    def close(self) -> None:
        """(The model and data are freed with the object; kept for the context manager.)"""

    def __enter__(self) -> MujocoWorld:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    # -- the state --------------------------------------------------------------------
    def forward(self) -> None:
        """Recompute every body's pose from qpos and the mocap base (kinematics only)."""
        mujoco.mj_kinematics(self.model, self.data)

    def set_base_pose(self, x: float, y: float, yaw: float) -> None:
        self.data.mocap_pos[self.mocap] = (x, y, 0.0)
        self.data.mocap_quat[self.mocap] = _wxyz(yaw_quat(yaw))

    def base_pose(self) -> tuple[float, float, float]:
        x, y, _ = self.data.mocap_pos[self.mocap]
        w, _, _, z = self.data.mocap_quat[self.mocap]
        return float(x), float(y), float(2.0 * np.arctan2(z, w))

    def set_joint_positions(self, values: dict[str, float]) -> None:
        qpos = self.data.qpos
        for name, value in values.items():
            qpos[self.robot_qpos[name]] = value

    def joint_positions(self, names: list[str] | None = None) -> dict[str, float]:
        names = list(self.robot_qpos) if names is None else names
        return {n: float(self.data.qpos[self.robot_qpos[n]]) for n in names}

    def world_joint_positions(self) -> dict[str, float]:
        return {n: float(self.data.qpos[a]) for n, a in self.world_qpos.items()}

    def body_pose(self, body: str) -> Pose:
        b = self._bodies[body]
        return (tuple(float(v) for v in self.data.xpos[b]), _xyzw(self.data.xquat[b]))

    def link_pose(self, link: str) -> Pose:
        """A robot link's frame in the world (after `forward`)."""
        return self.body_pose(ROBOT_PREFIX + link)

    def object_pose(self, name: str) -> Pose:
        a = self.item_qpos[name]
        q = self.data.qpos
        return (float(q[a]), float(q[a + 1]), float(q[a + 2])), _xyzw(q[a + 3:a + 7])

    def set_object_pose(self, name: str, position: Vec3, orientation: Quat) -> None:
        a, v = self.item_qpos[name], self.item_dof[name]
        self.data.qpos[a:a + 3] = position
        self.data.qpos[a + 3:a + 7] = _wxyz(orientation)
        self.data.qvel[v:v + 6] = 0.0

    def object_speed(self, name: str) -> tuple[float, float]:
        """Linear and angular speed of a free item."""
        v = self.item_dof[name]
        return (float(np.linalg.norm(self.data.qvel[v:v + 3])),
                float(np.linalg.norm(self.data.qvel[v + 3:v + 6])))

    # -- drawers and doors ------------------------------------------------------------
    def link_matrix(self, link: str) -> np.ndarray:
        b = self._bodies[link]
        out = np.eye(4)
        out[:3, :3] = self.data.xmat[b].reshape(3, 3)
        out[:3, 3] = self.data.xpos[b]
        return out

    def container_of_joint(self, joint: str) -> Container | None:
        return next((c for c in self.containers.values() if c.joint == joint), None)

    def items_inside(self, container: Container, exclude: set[str] | None = None) -> list[str]:
        """Items standing inside a container now (by where they are)."""
        frame = np.linalg.inv(self.link_matrix(container.inside_link))
        (x0, y0, z0), (x1, y1, z1) = container.inside_min, container.inside_max
        out = []
        for name in self.item_qpos:
            if exclude and name in exclude:
                continue
            x, y, z = frame[:3, :3] @ np.asarray(self.object_pose(name)[0]) + frame[:3, 3]
            if x0 <= x <= x1 and y0 <= y <= y1 and z0 - 0.02 <= z <= z1:
                out.append(name)
        return out

    def set_world_joint(self, name: str, value: float, exclude: set[str] | None = None) -> None:
        """Move a drawer or door; items inside a drawer move with it (but `exclude`)."""
        container = self.container_of_joint(name)
        carried = []
        if container is not None and container.inside_link == container.link:
            inverse = np.linalg.inv(self.link_matrix(container.link))
            carried = [(item, inverse @ pose_matrix(*self.object_pose(item)))
                       for item in self.items_inside(container, exclude)]
        self.data.qpos[self.world_qpos[name]] = value
        self.data.qvel[self.world_dof[name]] = 0.0
        if carried:
            self.forward()
            frame = self.link_matrix(container.link)
            for item, relative in carried:
                self.set_object_pose(item, *matrix_pose(frame @ relative))

    # -- simulation -------------------------------------------------------------------
    def step(self, count: int) -> None:
        mujoco.mj_step(self.model, self.data, nstep=count)

    def contacts(self) -> list[tuple[str, str, float]]:
        """The contacts now: (body, body, penetration depth m >= 0)."""
        m, d = self.model, self.data
        out = []
        for c in d.contact[:d.ncon]:
            a = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, int(m.geom_bodyid[c.geom1]))
            b = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, int(m.geom_bodyid[c.geom2]))
            out.append((a or "world", b or "world", max(0.0, -float(c.dist))))
        return out

    def snapshot(self) -> Snapshot:
        return Snapshot(self.data.qpos.copy(), self.data.mocap_pos.copy(),
                        self.data.mocap_quat.copy())

    def restore(self, snap: Snapshot) -> None:
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[:] = snap.qpos
        self.data.mocap_pos[:] = snap.mocap_pos
        self.data.mocap_quat[:] = snap.mocap_quat
        self.forward()
