"""`replay --check`, part two: is what was executed physically possible for the robot?

From the recorded states alone (no planner code):

- grip: the fingertips of a gripper are at most `GRIP_TOLERANCE_M` inside what it holds
  (an item, or a drawer's or door's handle while the action opening or closing it runs
  and the fingers are not open):
  held, not magnetised; measured as the collision check measures (surface points);
- tilt: an item whose item file says it stays upright never tilts by more than its
  tolerance (held or standing);
- base: the base's accelerations, by finite differences of consecutive states (from rest
  before the first and to rest after the last), within the limits the trace's header
  states (or cramlite's defaults), with `ACCEL_TOLERANCE` for the differencing;
- joints: each joint's acceleration likewise, within its velocity limit (the URDF's, or
  the header's where tighter) reached in `ACCELERATION_TIME_S` (the URDF gives no
  acceleration limits: the assumption the arm's timing makes), with `ACCEL_TOLERANCE` and
  the trace's rounding (6 decimals) for the differencing; a mimic joint follows its
  leader and is not checked on its own;
- yaw: at the end, an item put at a target of the setup (setting the table; clearing up
  into its container) stands within `YAW_TOLERANCE_DEG` of the target's yaw, up to the
  item's symmetry;
- support: an item out of the hand stands on something (a surface, a drawer's or the
  cupboard's inside, another item, the floor) wherever it comes to be: its lowest points
  at most `SUPPORT_GAP_M` above it; one let go in the air is found with its height;
- speeds: the base's speed and turning rate and each joint's velocity, averaged over each
  step, within the same limits (an average never exceeds the peak a timed profile keeps
  to), with `ACCEL_TOLERANCE` and the rounding;
- hold: a held item's bounds within `ATTACH_REACH_M` of its gripper's tool frame (the
  hand holds what is between its fingers, not an item beside it or in the other hand's
  place), and no heavier than `HAND_PAYLOAD_KG`;
- unheld: an item no hand holds stays where it was let go (or started), in the frame of
  the drawer it stands in, or falls: it may shift `UNHELD_SHIFT_M` from there (settling),
  sideways more only as far as twice what it dropped, never up; taken into a hand, it does
  not jump into it;
- impossible states: a joint beyond the URDF's limits (as the header states them), an
  object's quaternion that is not a rotation, a base nowhere near any kitchen;
- cut short: a header that promises an end mark (`end_marked`) and no state marked
  `"end": true` last (the trial was interrupted, or the trace lost its last lines).

Each finding names the thing, the value and the limit, the robot time and the trace line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cramlite.motion.base_timing import BaseLimits
from cramlite.scene.geometry import placed_bounds
from cramlite.scene.scene import gap_to_bounds, shapes_bounds
from cramlite.scene.transforms import quat_yaw
from cramlite.trace.check import (
    TraceChecker,
    checker_for,
    depth_inside,
    object_frame,
    penetration,
)
from cramlite.trace.format import Trace
from cramlite.world.pr2 import ATTACH_REACH_M, HAND_PAYLOAD_KG

GRIP_TOLERANCE_M = 0.002
#: Finite differences of states that step at most 2 cm may overshoot a profile that keeps
#: the limits by up to this share of the limit.
ACCEL_TOLERANCE = 0.05
YAW_TOLERANCE_DEG = 10.0
#: An item out of the hand rests on what is at most this far below its lowest points (a
#: physics engine's items settle within a millimetre or two of their support).
SUPPORT_GAP_M = 0.005
FINGERTIPS = ("gripper_l_finger_tip_link", "gripper_r_finger_tip_link")
#: A gripper whose fingers are open this far or wider grips nothing (an open hand that
#: brushes a handle on its way is a contact, judged by the penetration check).
OPEN_FINGER_RAD = 0.54
#: An item no hand holds may shift this much from where it was let go (a physics
#: engine's settling is under 0.3 mm a step), sideways more only as far as twice what it
#: dropped (a fall, tipping over).
UNHELD_SHIFT_M = 0.01


@dataclass(frozen=True)
class Finding:
    """One thing the robot could not have done so."""

    #: grip | tilt | base acceleration | base speed | joint acceleration | joint speed |
    #: hold | payload | unheld | yaw | support | joint limit | orientation | base | header |
    #: cut short
    kind: str
    what: str
    value: float
    limit: float
    unit: str
    t: float
    line: int

    def describe(self) -> str:
        if self.kind == "cut short":  # (no value to give)
            return f"{self.kind}: {self.what} (t={self.t:.2f} s, line {self.line})"
        return (f"{self.kind}: {self.what}: {self.value:g} {self.unit} (at most {self.limit:g} "
                f"{self.unit}) at t={self.t:.2f} s, line {self.line}")


def physics_findings(trace: Trace, checker: TraceChecker | None = None) -> list[Finding]:
    """Every finding of the checks above (the worst of each kind and thing)."""
    checker = checker or checker_for(trace)
    worst: dict[tuple[str, str], Finding] = {}

    def note(finding: Finding) -> None:
        key = (finding.kind, finding.what)
        if key not in worst or finding.value > worst[key].value:
            worst[key] = finding

    for check in (_grips(trace, checker), _tilts(trace, checker), _base_accelerations(trace),
                  _joint_accelerations(trace), _yaws(trace, checker), _supports(trace, checker),
                  _impossible(trace), _speeds(trace), _holds(trace, checker),
                  _unheld(trace, checker)):
        for finding in check:
            note(finding)
    if trace.cut_short:
        last = trace.states[-1]
        note(Finding("cut short", "the trace stops without the state marked \"end\" its "
                     "header promises: the trial was interrupted, or lines were lost",
                     0.0, 0.0, "", float(last["t"]), len(trace.states) + 1))
    return sorted(worst.values(), key=lambda f: (f.kind, -f.value))


#: A pose's quaternion may be this far from unit length (the trace's 6 digits).
QUATERNION_TOLERANCE = 1e-3
#: A base this far from the world's origin is nowhere in any kitchen (m).
MAX_BASE_DISTANCE_M = 100.0


def _impossible(trace: Trace):
    """States no robot can be in: joints beyond the URDF's limits (the header's), object
    orientations that are not rotations, a base far outside any kitchen."""
    from cramlite.scene.models import pr2_model

    claimed = (trace.header.get("robot") or {}).get("joint_limits") or {}
    joints = trace.header["joints"]
    # (a mimic joint follows its leader, as the URDF's mimic tag says; its own limits are
    # not the motion's: the PR2's right finger roots turn opposite to their limits' sign)
    model = pr2_model()
    followers = {m.joint for m in model.mimics}
    bounds = []
    for i, name in enumerate(joints):
        joint = model.joints.get(name)
        if joint is None or name in followers or joint.kind == "continuous":
            continue
        # the URDF's limits, or the header's where they are tighter: a header cannot make
        # a joint reach further than the robot's own URDF lets it
        lower, upper = joint.lower, joint.upper
        given = claimed.get(name)
        if isinstance(given, list) and len(given) >= 2 and all(
                isinstance(v, int | float) and math.isfinite(v) for v in given[:2]):
            if given[0] < lower - 1e-6 or given[1] > upper + 1e-6:
                yield Finding("header", f"joint_limits of {name} [{given[0]:g}, "
                              f"{given[1]:g}] wider than the URDF's [{lower:g}, {upper:g}]",
                              round(max(lower - given[0], given[1] - upper), 4), 0.0, "",
                              0.0, 1)
            lower, upper = max(lower, given[0]), min(upper, given[1])
        bounds.append((i, name, lower, upper))
    for k, state in enumerate(trace.states):
        line = k + 2
        for i, name, lower, upper in bounds:
            q = state["q"][i]
            beyond = max((lower - q) if lower is not None else 0.0,
                         (q - upper) if upper is not None else 0.0)
            if beyond > 1e-4:
                joint = model.joints.get(name)
                unit = "m" if joint is not None and joint.kind == "prismatic" else "rad"
                span = f"[{'-inf' if lower is None else f'{lower:g}'}, " \
                       f"{'inf' if upper is None else f'{upper:g}'}]"
                yield Finding("joint limit", f"{name} at {q:g} {unit}, its limits {span}",
                              round(beyond, 4), 0.0, unit, state["t"], line)
        for name, pose in state["objects"].items():
            norm = math.sqrt(sum(v * v for v in pose[3:]))
            if abs(norm - 1.0) > QUATERNION_TOLERANCE:
                yield Finding("orientation", f"{name}'s quaternion has norm {norm:g}, not 1",
                              round(abs(norm - 1.0), 4), QUATERNION_TOLERANCE, "", state["t"],
                              line)
        x, y = state["base"][0], state["base"][1]
        if math.hypot(x, y) > MAX_BASE_DISTANCE_M:
            yield Finding("base", "the base outside any kitchen", round(math.hypot(x, y), 1),
                          MAX_BASE_DISTANCE_M, "m", state["t"], line)


def _finger(trace: Trace, state: dict, arm: str) -> float:
    """The leading finger joint's angle of a gripper (open if the trace has none)."""
    name = f"{arm[0]}_gripper_l_finger_joint"
    joints = trace.header["joints"]
    return float(state["q"][joints.index(name)]) if name in joints else math.inf


def _depth(tip, placed: np.ndarray, body, where: np.ndarray, cache: dict) -> float:
    """How deep a fingertip is inside a body; while an item is held its fingertips keep
    their pose relative to it, so the answer is kept per relative pose (to 0.1 mm)."""
    relative = np.linalg.solve(where, placed)
    key = (id(tip), id(body), np.round(relative[:3], 4).tobytes())
    if key not in cache:
        cache[key] = penetration(tip, placed, body, where, np.full(3, -1e9),
                                 np.full(3, 1e9), GRIP_TOLERANCE_M)
    return cache[key]


def _grips(trace: Trace, checker: TraceChecker):
    handles = checker.handles
    cache: dict = {}
    for i, state in enumerate(trace.states):
        held = state["held"]
        action = state.get("action") or {}
        gripped = handles.get(action.get("object"))
        if not held and gripped is None:
            continue
        robot = checker.robot_frames(state)
        grips: list[tuple[str, list]] = []
        for name, arm in held.items():
            if name in state["objects"]:
                frame = object_frame(state["objects"][name])
                grips.append((arm, [(body, frame @ body.shape.in_link)
                                    for body in checker.item_bodies[name]]))
        closing = [arm for arm in ("right", "left") if arm not in held.values()
                   and _finger(trace, state, arm) < OPEN_FINGER_RAD]
        if gripped is not None and closing:
            kitchen = checker.kitchen_frames(state)
            bodies = [(body, kitchen[body.owner] @ body.shape.in_link)
                      for body in checker.kitchen_bodies if body.owner == gripped]
            grips += [(arm, bodies) for arm in closing]
        for arm, bodies in grips:
            for tip in FINGERTIPS:
                link = f"{arm[0]}_{tip}"
                for tip_body in (b for b in checker.robot_bodies if b.owner == link):
                    placed = robot[link] @ tip_body.shape.in_link
                    for body, where in bodies:
                        depth = _depth(tip_body, placed, body, where, cache)
                        if depth > GRIP_TOLERANCE_M:
                            yield Finding("grip", f"{link} inside {body.label}",
                                          round(depth * 1000, 1), GRIP_TOLERANCE_M * 1000,
                                          "mm", state["t"], i + 2)


def _tilts(trace: Trace, checker: TraceChecker):
    upright = {name: math.radians(model.kind.upright_tolerance_deg)
               for name, model in checker.items.items() if model.kind.upright}
    for i, state in enumerate(trace.states):
        for name, limit in upright.items():
            pose = state["objects"].get(name)
            if pose is None:
                continue
            frame = object_frame(pose)
            tilt = math.acos(max(-1.0, min(1.0, float(frame[2, 2]))))
            if tilt > limit + 1e-6:
                yield Finding("tilt", name, round(math.degrees(tilt), 1),
                              round(math.degrees(limit), 1), "deg", state["t"], i + 2)


def _base_limits(trace: Trace) -> tuple[BaseLimits, list[Finding]]:
    """The PR2's base limits, or the header's where tighter; a header's limit beyond the
    PR2's is a finding (read_trace checked the header's are numbers > 0)."""
    header = trace.header.get("base_limits") or {}
    pr2 = BaseLimits()
    values, findings = {}, []
    for key in BaseLimits.__dataclass_fields__:
        own = getattr(pr2, key)
        value = float(header.get(key, own))
        if value > own + 1e-9:
            findings.append(Finding("header", f"base_limits {key} {value:g} beyond the "
                                    f"PR2's {own:g}", value, own, "", 0.0, 1))
        values[key] = min(value, own)
    return BaseLimits(**values), findings


def _base_accelerations(trace: Trace):
    limits, findings = _base_limits(trace)
    yield from findings
    states = trace.states
    if len(states) < 2:
        return
    t = np.array([s["t"] for s in states])
    base = np.array([s["base"] for s in states], dtype=float)
    base[:, 2] = np.unwrap(base[:, 2])
    dt = np.diff(t)
    step = np.diff(base, axis=0)
    moving = np.any(np.abs(step) > 1e-9, axis=1)
    # velocity of each step (0 where the base stands); a step of no time that moves it
    # is a jump (infinite acceleration)
    with np.errstate(divide="ignore", invalid="ignore"):
        v = np.where(dt[:, None] > 1e-9, step / dt[:, None], 0.0)
    for k in np.flatnonzero(moving & (dt <= 1e-9)):
        yield Finding("base acceleration", "a jump of the base", math.inf,
                      limits.accel_m_s2, "m/s^2", float(t[k + 1]), int(k) + 3)
    a, _ = _from_rest_to_rest(v, dt)
    if trace.cut_short:  # (not at rest after its last state: it was cut there)
        a = a[:-1]
    xy, yaw = np.hypot(a[:, 0], a[:, 1]), np.abs(a[:, 2])
    for values, limit, what, unit in ((xy, limits.accel_m_s2, "driving", "m/s^2"),
                                      (yaw, limits.turn_accel_rad_s2, "turning", "rad/s^2")):
        over = np.flatnonzero(values > limit * (1 + ACCEL_TOLERANCE) + 1e-6)
        for k in over:
            line = int(min(k, len(states) - 1)) + 2
            yield Finding("base acceleration", what, round(float(values[k]), 2),
                          round(limit, 2), unit, float(t[min(k, len(t) - 1)]), line)


def _from_rest_to_rest(v: np.ndarray, dt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Accelerations (steps + 1 x coordinates) at each junction of steps of velocity `v`
    lasting `dt`, from rest before the first and to rest after the last: the change of
    velocity over the time between the steps' middles (0 where that is no time); and that
    time."""
    rest = np.zeros((1, v.shape[1]))
    lengths = np.concatenate([[0.0], dt, [0.0]])
    gap = (lengths[:-1] + lengths[1:]) / 2
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(gap[:, None] > 1e-9, np.diff(np.vstack([rest, v, rest]), axis=0) /
                     gap[:, None], 0.0)
    return a, gap


#: A trace's positions are written to 6 decimals: differencing them twice may be off by
#: this much over the product of the two steps' lengths (s^2).
ROUNDING_M = 2e-6


def _joint_columns(trace: Trace) -> tuple[list[int], list[float], list[tuple[str, str]],
                                          list[bool]]:
    """The joints whose motion is checked (not a mimic follower: it follows its leader):
    their columns of `q`, velocity limits (the URDF's, or the header's where tighter),
    (name, unit) and whether each turns without end."""
    from cramlite.scene.models import pr2_model

    model = pr2_model()
    followers = {m.joint for m in model.mimics}
    claimed = (trace.header.get("robot") or {}).get("joint_limits") or {}
    columns, velocities, names, turning = [], [], [], []
    for i, name in enumerate(trace.header["joints"]):
        joint = model.joints.get(name)
        if joint is None or name in followers or not joint.velocity > 0:
            continue
        velocity = joint.velocity
        given = claimed.get(name)
        if isinstance(given, list) and len(given) >= 3 and \
                isinstance(given[2], int | float) and 0 < given[2] < velocity:
            velocity = float(given[2])
        turning.append(joint.kind == "continuous")
        columns.append(i)
        velocities.append(velocity)
        names.append((name, "m" if joint.kind == "prismatic" else "rad"))
    return columns, velocities, names, turning


def _joint_steps(trace: Trace, columns: list[int], turning: list[bool],
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The states' times, and each step's length and joints' change."""
    t = np.array([s["t"] for s in trace.states], dtype=float)
    q = np.array([s["q"] for s in trace.states], dtype=float)[:, columns]
    # (a continuous joint's angle may be written a turn apart: the same angle)
    q[:, turning] = np.unwrap(q[:, turning], axis=0)
    return t, np.diff(t), np.diff(q, axis=0)


def _joint_accelerations(trace: Trace):
    """Each joint's acceleration between consecutive steps (a step of no time that moves
    a joint is a jump; one that moves nothing is the same state written twice), from rest
    before the first state and to rest after the last."""
    from cramlite.motion.trajectory import ACCELERATION_TIME_S

    states = trace.states
    if len(states) < 2:
        return
    columns, velocities, names, turning = _joint_columns(trace)
    if not columns:
        return
    limits = [velocity / ACCELERATION_TIME_S for velocity in velocities]
    names = [(name, f"{unit}/s^2") for name, unit in names]
    t, dt, dq = _joint_steps(trace, columns, turning)
    still = dt <= 1e-9
    for k in np.flatnonzero(still & np.any(np.abs(dq) > ROUNDING_M, axis=1)):
        j = int(np.argmax(np.abs(dq[k])))
        yield Finding("joint acceleration", f"a jump of {names[j][0]}", math.inf, limits[j],
                      names[j][1], float(t[k + 1]), int(k) + 3)
    steps = np.flatnonzero(~still)  # (the state each step ends at: steps + 1)
    if not len(steps):
        return
    a, gap = _from_rest_to_rest(dq[steps] / dt[steps, None], dt[steps])
    a = np.abs(a)
    lengths = np.concatenate([[0.0], dt[steps], [0.0]])
    # (the shorter of the two steps at a junction; the one step at either end)
    shorter = np.minimum(lengths[:-1], lengths[1:])
    shorter = np.where(shorter > 0, shorter, np.maximum(lengths[:-1], lengths[1:]))
    allowed = np.array(limits) * (1 + ACCEL_TOLERANCE) + (ROUNDING_M / (shorter * gap))[:, None]
    if trace.cut_short:  # (not at rest after its last state: it was cut there)
        a, allowed = a[:-1], allowed[:-1]
    for k, j in zip(*np.nonzero(a > allowed), strict=True):
        # (between step k-1 and step k: at the state step k-1 ends at)
        state = int(steps[k - 1]) + 1 if k > 0 else int(steps[0])
        yield Finding("joint acceleration", names[j][0], round(float(a[k, j]), 2),
                      round(limits[j], 3), names[j][1], float(t[state]), state + 2)


def _speeds(trace: Trace):
    """The base's speed and turning rate and each joint's velocity over each step of time
    (a step's average: a timed profile within its limits never exceeds them on average),
    within their limits (`ACCEL_TOLERANCE`, and the rounding over the step)."""
    states = trace.states
    if len(states) < 2:
        return
    columns, velocities, names, turning = _joint_columns(trace)
    t, dt, dq = _joint_steps(trace, columns, turning)
    steps = np.flatnonzero(dt > 1e-9)  # (a step of no time is judged as a jump)
    if not len(steps):
        return
    limits, _ = _base_limits(trace)
    base = np.array([s["base"] for s in states], dtype=float)
    base[:, 2] = np.unwrap(base[:, 2])
    step = np.diff(base, axis=0)[steps]
    span = dt[steps]
    slack = ROUNDING_M / span
    for values, limit, what, unit in (
            (np.hypot(step[:, 0], step[:, 1]) / span, limits.speed_m_s, "driving", "m/s"),
            (np.abs(step[:, 2]) / span, limits.turn_rad_s, "turning", "rad/s")):
        for k in np.flatnonzero(values > limit * (1 + ACCEL_TOLERANCE) + slack):
            yield Finding("base speed", what, round(float(values[k]), 3), round(limit, 3),
                          unit, float(t[steps[k] + 1]), int(steps[k]) + 3)
    if not columns:
        return
    v = np.abs(dq[steps]) / span[:, None]
    allowed = np.array(velocities) * (1 + ACCEL_TOLERANCE) + slack[:, None]
    for k, j in zip(*np.nonzero(v > allowed), strict=True):
        yield Finding("joint speed", names[j][0], round(float(v[k, j]), 3),
                      round(velocities[j], 3), f"{names[j][1]}/s", float(t[steps[k] + 1]),
                      int(steps[k]) + 3)


def _holds(trace: Trace, checker: TraceChecker):
    """Each held item within reach of its gripper's fingers (its bounds within
    `ATTACH_REACH_M` of the tool frame), and no heavier than a hand may hold."""
    bounds: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    last: dict[str, tuple] = {}
    for i, state in enumerate(trace.states):
        robot = None
        for name, arm in state["held"].items():
            model = checker.items.get(name)
            if model is None or name not in state["objects"]:
                continue
            if model.mass_kg > HAND_PAYLOAD_KG:
                yield Finding("payload", f"{name} held by the {arm} hand",
                              round(model.mass_kg, 3), HAND_PAYLOAD_KG, "kg", state["t"],
                              i + 2)
            key = (arm, tuple(state["q"]), tuple(state["base"]),
                   tuple(state["objects"][name]))
            if last.get(name) == key:
                continue
            last[name] = key
            if name not in bounds:
                bounds[name] = shapes_bounds(model.shapes)
            if robot is None:
                robot = checker.robot_frames(state)
            gap = gap_to_bounds(robot[f"{arm[0]}_gripper_tool_frame"][:3, 3],
                                object_frame(state["objects"][name]), *bounds[name])
            if gap > ATTACH_REACH_M + 1e-3:
                yield Finding("hold", f"{name} held by the {arm} hand, its bounds away from "
                              "the fingers", round(gap * 100, 1), ATTACH_REACH_M * 100, "cm",
                              state["t"], i + 2)


def _unheld(trace: Trace, checker: TraceChecker):
    """An item no hand holds stays where the hand let it go (or where it was at the
    start), in the frame of the drawer it stands in, except by falling: measured from
    there, not step by step (a creep of 9 mm a state, or moves in no time, add up), it
    may shift `UNHELD_SHIFT_M`, sideways more only as far as twice what it dropped (an
    item that falls may tip over), and never rise. An item taken into a hand does not
    jump into it: from its last state out of the hand to its first in it, at most
    `UNHELD_SHIFT_M`."""
    states = trace.states
    kitchen: dict[tuple, dict[str, np.ndarray]] = {}

    def frames(k: int) -> dict[str, np.ndarray]:
        key = tuple(states[k]["w"])
        if key not in kitchen:
            kitchen[key] = checker.kitchen_frames(states[k])
        return kitchen[key]

    def placed(k: int, name: str, container) -> np.ndarray:
        """The item's position at state k, in the container's inside frame (or the
        world's)."""
        point = np.array(states[k]["objects"][name][:3], dtype=float)
        if container is None:
            return point
        return np.linalg.solve(frames(k)[container.inside_link], [*point, 1.0])[:3]

    anchors: dict[str, tuple[object, np.ndarray]] = {}
    for k, state in enumerate(states):
        before = states[k - 1] if k else None
        for name, pose in state["objects"].items():
            was_held = before is not None and name in before["held"]
            if name in state["held"]:
                anchors.pop(name, None)
                if before is not None and not was_held and name in before["objects"]:
                    jump = math.dist(before["objects"][name][:3], pose[:3])
                    if jump > UNHELD_SHIFT_M:  # (taken: the hand closed on it where it was)
                        yield Finding("unheld", f"{name} jumped into the hand",
                                      round(jump * 100, 1), UNHELD_SHIFT_M * 100, "cm",
                                      state["t"], k + 2)
                continue
            if name not in anchors:  # (where the hand let it go, or where it starts)
                origin = k - 1 if was_held and name in before["objects"] else k
                point = np.array(states[origin]["objects"][name][:3], dtype=float)
                container = next((c for c in checker.containers.values() if _in_box(
                    np.linalg.solve(frames(origin)[c.inside_link], [*point, 1.0])[:3], c)),
                    None)
                anchors[name] = (container, placed(origin, name, container))
                if origin == k:
                    continue
            container, a = anchors[name]
            b = placed(k, name, container)
            drop = max(0.0, float(a[2] - b[2]))
            shift = max(float(np.hypot(*(b - a)[:2])) - 2 * drop, float(b[2] - a[2]))
            if shift > UNHELD_SHIFT_M:
                yield Finding("unheld", f"{name} moved with no hand holding it",
                              round(shift * 100, 1), UNHELD_SHIFT_M * 100, "cm", state["t"],
                              k + 2)


def _in_box(local: np.ndarray, container, margin: float = 0.02) -> bool:
    """Is a point (in a container's inside frame) inside it, or within `margin`?"""
    (x0, y0, z0), (x1, y1, z1) = container.inside_min, container.inside_max
    return bool(x0 - margin <= local[0] <= x1 + margin and y0 - margin <= local[1] <= y1 + margin
                and z0 - margin <= local[2] <= z1)


def _supports(trace: Trace, checker: TraceChecker):
    """Each pose an item takes out of the hand (checked once per pose, and again where a
    drawer or door moves or an item is taken or let go): is there something within
    `SUPPORT_GAP_M` below its lowest points? If not, how far below the next thing is."""
    last: dict[str, tuple] = {}
    points: dict[int, np.ndarray] = {}  # each item body's surface points (its frame)
    everywhere = (np.full(3, -1e3), np.full(3, 1e3))
    for body in (b for bodies in checker.item_bodies.values() for b in bodies):
        points[id(body)] = body.points_within(*everywhere, True)
    for i, state in enumerate(trace.states):
        kitchen = resting = None
        for name, pose in state["objects"].items():
            if name in state["held"] or name not in checker.item_bodies:
                last.pop(name, None)
                continue
            # (again where its drawer moves, or anything is taken or put down: what it
            # stood on may have gone)
            key = (tuple(pose), tuple(state["w"]), tuple(sorted(state["held"])))
            if last.get(name) == key:
                continue
            last[name] = key
            if kitchen is None:  # (once a state, for every item checked in it)
                frames = checker.kitchen_frames(state)
                kitchen = _Boxed([(body, frames[body.owner] @ body.shape.in_link)
                                  for body in checker.kitchen_bodies])
                resting = _Boxed([(body, object_frame(state["objects"][other]) @
                                   body.shape.in_link)
                                  for other, bodies in checker.item_bodies.items()
                                  if other in state["objects"] and other not in state["held"]
                                  for body in bodies])
            gap = _gap_below(checker, name, state, kitchen, resting, points)
            if gap > SUPPORT_GAP_M:
                yield Finding("support", f"{name} rests on nothing", round(gap * 100, 1),
                              SUPPORT_GAP_M * 100, "cm", state["t"], i + 2)


class _Boxed:
    """Placed bodies with their world bounding boxes, to pick those under a few points."""

    def __init__(self, placed: list[tuple]):
        self.placed = placed
        self.lo, self.hi = placed_bounds([body.shape for body, _ in placed],
                                         np.array([where for _, where in placed]))

    def under(self, lo: np.ndarray, hi: np.ndarray, top: float) -> list[tuple]:
        """The bodies whose boxes meet lo..hi in x and y and reach below `top`."""
        keep = np.all(self.lo[:, :2] <= hi, axis=1) & np.all(self.hi[:, :2] >= lo, axis=1) \
            & (self.lo[:, 2] < top)
        return [self.placed[k] for k in np.flatnonzero(keep)]


def _gap_below(checker: TraceChecker, name: str, state: dict, kitchen: _Boxed,
               resting: _Boxed, points: dict[int, np.ndarray]) -> float:
    """How far the lowest points of an item are above what is under them (the kitchen, or
    another of the `resting` items; to 1 mm; 0 if within `SUPPORT_GAP_M`), the floor at
    the latest."""
    frame = object_frame(state["objects"][name])
    world = []
    for body in checker.item_bodies[name]:
        placed = frame @ body.shape.in_link
        world.append(points[id(body)] @ placed[:3, :3].T + placed[:3, 3])
    every = np.vstack(world)
    low = float(every[:, 2].min())
    bottom = every[every[:, 2] <= low + 0.002]
    lo, hi = bottom[:, :2].min(axis=0), bottom[:, :2].max(axis=0)
    own = {id(body) for body in checker.item_bodies[name]}
    others = kitchen.under(lo, hi, low) + [(body, where) for body, where
                                           in resting.under(lo, hi, low)
                                           if id(body) not in own]

    def meets(drop: float) -> bool:
        lowered = bottom - (0.0, 0.0, drop)
        return any(depth_inside(lowered, body, where, 0.0) > 0.0 for body, where in others)

    if low <= SUPPORT_GAP_M or meets(SUPPORT_GAP_M):
        return 0.0
    above = SUPPORT_GAP_M
    for drop in np.arange(0.01, low, 0.01):
        if meets(float(drop)):  # somewhere between the last step and this one: to 1 mm
            below = float(drop)
            while below - above > 0.001:
                middle = (above + below) / 2
                above, below = (above, middle) if meets(middle) else (middle, below)
            return above
        above = float(drop)
    return max(0.0, low)  # (the floor)


def _yaws(trace: Trace, checker: TraceChecker):
    if not trace.states:
        return
    plan = trace.header.get("plan")
    last = trace.states[-1]
    for spec in checker.setup.items:
        if plan == "set-table":
            target = spec.target
        elif plan == "clear-table" and spec.container:
            target = spec.pose
        else:
            continue
        pose = last["objects"].get(spec.name)
        if pose is None or spec.name in last["held"]:
            continue
        if math.dist(pose[:2], (target.x, target.y)) > 0.1:
            continue  # not put there (the trial's result says so; no yaw to judge)
        model = checker.items[spec.name]
        error = math.degrees(model.kind.yaw_error(quat_yaw(pose[3:]), target.yaw,
                                                  model.yaw_symmetry_deg))
        if error > YAW_TOLERANCE_DEG:
            yield Finding("yaw", f"{spec.name} at its target", round(error, 2),
                          YAW_TOLERANCE_DEG, "deg", last["t"], len(trace.states) + 1)
