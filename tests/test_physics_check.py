"""`replay --check`'s physics: a trace of an honest trial passes, and each way a trace can
be physically impossible (fingers through what they hold, a spilled cup, a base that
jumps, an item put down turned) is found, named and located, from the trace alone."""

from __future__ import annotations

import copy
import json
import math
import re

import pytest

from cramlite.trace import read_trace
from cramlite.trace.physics import physics_findings
from cramlite.trial import TrialRunner
from tests.conftest import run_cli


@pytest.fixture(scope="module")
def trace(tmp_path_factory):
    path = tmp_path_factory.mktemp("physics") / "v1.jsonl"
    with TrialRunner("v1", backend="kinematic") as runner:
        result = runner.run("baseline", seed=0, trace=path)
    assert result.success, result.failures
    return read_trace(path)


def _rotated(quat, axis: str, degrees: float) -> list[float]:
    half = math.radians(degrees) / 2
    turn = [0.0, 0.0, 0.0, math.cos(half)]
    turn["xyz".index(axis)] = math.sin(half)
    (x1, y1, z1, w1), (x2, y2, z2, w2) = turn, quat  # (turn * quat, x y z w)
    return [w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2, w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2, w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2]


def _held_states(trace, name: str) -> list[int]:
    return [i for i, s in enumerate(trace.states) if name in s["held"]]


def test_an_honest_trial_has_no_findings_and_holds_with_fingers_at_contact(trace) -> None:
    assert physics_findings(trace) == []
    # the fingers stop where they touch: holding the cup (8 cm across) they stand open
    joints = trace.header["joints"]
    held = _held_states(trace, "cup")
    assert held
    arm = trace.states[held[0]]["held"]["cup"]
    finger = joints.index(f"{arm[0]}_gripper_l_finger_joint")
    angles = {round(trace.states[i]["q"][finger], 3) for i in held}
    assert min(angles) > 0.3, angles  # (closed would be 0; 9.2 cm open is 0.548)


def test_fingers_closed_through_the_held_item_are_found(trace) -> None:
    bad = copy.deepcopy(trace)
    joints = bad.header["joints"]
    for state in bad.states:
        for arm in state["held"].values():
            for name in joints:
                if name.startswith(f"{arm[0]}_gripper_") and "finger" in name:
                    state["q"][joints.index(name)] = 0.0
    found = physics_findings(bad)
    grips = [f for f in found if f.kind == "grip"]
    assert grips, found
    assert {f.what.split(" inside ")[1].strip("'") for f in grips} >= {"cup", "milk"}
    assert all(f.value > 2 for f in grips)


def test_a_carried_cup_tipped_over_is_found_with_its_time_and_line(trace) -> None:
    bad = copy.deepcopy(trace)
    held = _held_states(bad, "cup")
    i = held[len(held) // 2]
    pose = bad.states[i]["objects"]["cup"]
    pose[3:] = _rotated(pose[3:], "x", 120)
    found = physics_findings(bad)
    assert [(f.kind, f.what, f.line) for f in found] == [("tilt", "cup", i + 2)]
    assert found[0].value == pytest.approx(120, abs=1) and found[0].limit == 15
    assert found[0].t == bad.states[i]["t"]


def test_a_jump_of_the_base_is_found(trace) -> None:
    bad = copy.deepcopy(trace)
    moving = [i for i in range(1, len(bad.states) - 1)
              if bad.states[i]["base"] != bad.states[i - 1]["base"]]
    i = moving[len(moving) // 2]
    bad.states[i]["base"][0] += 0.05  # 5 cm aside in one step of a drive
    found = physics_findings(bad)
    assert found and {f.kind for f in found} == {"base acceleration"}
    assert any(abs(f.line - (i + 2)) <= 1 for f in found)


def _moving_arm_state(trace, joint: str) -> int:
    """A state in the middle of a motion of `joint` (moving into it and out of it), its
    hand holding nothing (pushed aside, a hand would also move its fingers in the item)."""
    k = trace.header["joints"].index(joint)
    q = [s["q"][k] for s in trace.states]
    arm = {"r": "right", "l": "left"}[joint[0]]
    moving = [i for i in range(1, len(q) - 1)
              if q[i - 1] != q[i] != q[i + 1] and trace.states[i]["t"] > trace.states[i - 1]["t"]
              and arm not in trace.states[i]["held"].values()]
    return moving[len(moving) // 2]


def test_a_joint_whose_speed_jumps_is_found_with_its_time_and_line(trace) -> None:
    """A joint's acceleration, by finite differences of the states (the URDF gives only
    velocity limits: the limit is the velocity reached in ACCELERATION_TIME_S): a state
    pushed 3 cm of the way aside is a jump in speed there."""
    joint = "r_elbow_flex_joint"
    bad = copy.deepcopy(trace)
    i = _moving_arm_state(bad, joint)
    bad.states[i]["q"][bad.header["joints"].index(joint)] += 0.03
    found = physics_findings(bad)
    assert {f.kind for f in found} == {"joint acceleration"}, [f.describe() for f in found]
    (worst,) = [f for f in found if f.what == joint]
    assert abs(worst.line - (i + 2)) <= 1 and worst.value > worst.limit
    assert worst.limit == pytest.approx(3.3 / 0.25, abs=1e-3)  # (the URDF's 3.3 rad/s)
    assert worst.unit == "rad/s^2"


def test_a_joint_moved_in_no_time_is_a_jump_and_a_turn_of_a_continuous_one_is_not(
        trace) -> None:
    joints = trace.header["joints"]
    bad = copy.deepcopy(trace)
    i = _moving_arm_state(bad, "r_elbow_flex_joint")
    twin = copy.deepcopy(bad.states[i])
    twin["q"][joints.index("r_shoulder_pan_joint")] += 0.01
    bad.states.insert(i + 1, twin)  # (the same time, the shoulder 0.01 rad further)
    found = [f for f in physics_findings(bad) if f.kind == "joint acceleration"]
    assert any(f.what == "a jump of r_shoulder_pan_joint" and f.value == math.inf and
               f.line == i + 3 for f in found), [f.describe() for f in found]
    # a continuous joint written a whole turn apart is where it was
    turned = copy.deepcopy(trace)
    wrist = joints.index("r_wrist_roll_joint")
    for state in turned.states[len(turned.states) // 2:]:
        state["q"][wrist] += 2 * math.pi
    assert physics_findings(turned) == []


def test_an_item_put_down_turned_is_found_up_to_its_symmetry(trace) -> None:
    for name, degrees, expected in (("breakfast-cereal", 90, True),
                                    ("breakfast-cereal", 180, False),  # (a box)
                                    ("milk", 90, False), ("milk", 45, True),  # (square)
                                    ("cup", 70, False)):  # (round)
        bad = copy.deepcopy(trace)
        pose = bad.states[-1]["objects"][name]
        pose[3:] = _rotated(pose[3:], "z", degrees)
        found = [f for f in physics_findings(bad) if f.kind == "yaw"]
        assert bool(found) == expected, (name, degrees, found)
        if expected:
            assert found[0].what == f"{name} at its target"
            assert found[0].value == pytest.approx(degrees if degrees < 90 else 90, abs=1)


def test_replay_check_prints_physics_findings_and_exits_1(trace, tmp_path) -> None:
    bad = copy.deepcopy(trace)
    i = _held_states(bad, "milk")[5]
    pose = bad.states[i]["objects"]["milk"]
    pose[3:] = _rotated(pose[3:], "y", 165)
    path = tmp_path / "tipped.jsonl"
    path.write_text("\n".join(json.dumps(r) for r in [bad.header, *bad.states]) + "\n")
    done = run_cli("replay", str(path), "--check")
    assert done.returncode == 1, done.stderr
    # (165 deg onto a milk carried within a degree of upright)
    assert re.search(r"not physical: tilt: milk: 16[4-6](\.\d)? deg \(at most 15 deg\)",
                     done.stdout)
    assert f"line {i + 2}" in done.stdout
    assert "Traceback" not in done.stderr


@pytest.mark.parametrize(("change", "kind"), [
    ("torso", "joint limit"), ("elbow", "joint limit"), ("quaternion", "orientation"),
    ("base", "base")])
def test_impossible_states_are_findings(trace, change: str, kind: str) -> None:
    """(The red-team's torso at 5 m, elbow at 100 rad, zero quaternion, base at 1e300 m:
    well-formed lines, so no exit 2, but no robot can be there.)"""
    bad = copy.deepcopy(trace)
    i = len(bad.states) // 2
    state = bad.states[i]
    joints = bad.header["joints"]
    if change == "torso":
        state["q"][joints.index("torso_lift_joint")] = 5.0
    elif change == "elbow":
        state["q"][joints.index("r_elbow_flex_joint")] = 100.0
    elif change == "quaternion":
        state["objects"]["cup"][3:] = [0.0, 0.0, 0.0, 0.0]
    else:
        state["base"][0] = 1e300
    found = [f for f in physics_findings(bad) if f.kind == kind]
    assert found and found[0].line == i + 2, physics_findings(bad)


def test_a_header_cannot_widen_the_robots_limits(trace) -> None:
    """(The red-team raised base_limits to 1e308 to hide a jump, and a header's joint
    limits could hide a torso at 5 m: the PR2's own limits hold, the claim is a finding.)"""
    bad = copy.deepcopy(trace)
    bad.header["base_limits"] = dict.fromkeys(bad.header["base_limits"], 1e308)
    moving = [i for i in range(1, len(bad.states) - 1)
              if bad.states[i]["base"] != bad.states[i - 1]["base"]]
    bad.states[moving[len(moving) // 2]]["base"][0] += 0.05
    torso = bad.header["joints"].index("torso_lift_joint")
    bad.header["robot"]["joint_limits"]["torso_lift_joint"] = [0.0, 10.0, 0.013]
    bad.states[len(bad.states) // 3]["q"][torso] = 5.0
    kinds = {f.kind for f in physics_findings(bad)}
    assert {"base acceleration", "joint limit", "header"} <= kinds
    claims = [f.what for f in physics_findings(bad) if f.kind == "header"]
    assert any("accel_m_s2 1e+308 beyond the PR2's 1" in c for c in claims)
    assert any("torso_lift_joint [0, 10] wider than the URDF's" in c for c in claims)
    assert not [f for f in physics_findings(trace) if f.kind == "header"]


def test_an_item_left_in_the_air_is_found_with_its_height(trace) -> None:
    """The cup put at its target, but 10 cm above the island: nothing under it (as the
    kinematic backend would leave an item let go in the air)."""
    bad = copy.deepcopy(trace)
    last_held = _held_states(bad, "cup")[-1]
    for state in bad.states[last_held + 1:]:
        state["objects"]["cup"][2] += 0.10
    found = physics_findings(bad)
    assert [(f.kind, f.what, f.line) for f in found] == [
        ("support", "cup rests on nothing", last_held + 3)], found
    assert found[0].value == pytest.approx(10.0, abs=0.15) and found[0].unit == "cm"
    assert found[0].t == bad.states[last_held + 1]["t"]
    # and 3 mm is a physics engine's settling, not a finding
    for state in bad.states[last_held + 1:]:
        state["objects"]["cup"][2] -= 0.097
    assert physics_findings(bad) == []


def test_an_item_whose_support_is_taken_away_is_found(trace) -> None:
    """The milk stood on the cup (as it could): when the cup is picked up, the milk hangs
    in the air, though it did not move."""
    from cramlite.trace.check import checker_for

    bad = copy.deepcopy(trace)
    top = max(b.shape.centre[2] + b.shape.half[2] for b in checker_for(bad).item_bodies["cup"])
    first_cup, first_milk = _held_states(bad, "cup")[0], _held_states(bad, "milk")[0]
    assert first_cup < first_milk  # (the baseline order takes the cup first)
    x, y, z = bad.states[0]["objects"]["cup"][:3]
    for state in bad.states[:first_milk]:
        state["objects"]["milk"][:3] = [x, y, z + top]
    found = physics_findings(bad)
    assert [(f.kind, f.what, f.line) for f in found] == [
        ("support", "milk rests on nothing", first_cup + 2)], found
    assert found[0].value == pytest.approx(top * 100, abs=0.15), found[0].value
