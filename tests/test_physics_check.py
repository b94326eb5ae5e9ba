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
    # (and, 5 cm in a step of ~30 ms, faster than the base drives)
    assert found and {f.kind for f in found} == {"base acceleration", "base speed"}
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
    # (and, as written, it rose 10 cm as the hand let go: unheld)
    assert {f.kind for f in found} == {"support", "unheld"}, found
    found = [f for f in found if f.kind == "support"]
    assert [(f.kind, f.what, f.line) for f in found] == [
        ("support", "cup rests on nothing", last_held + 3)], found
    assert found[0].value == pytest.approx(10.0, abs=0.15) and found[0].unit == "cm"
    assert found[0].t == bad.states[last_held + 1]["t"]
    # and 3 mm is a physics engine's settling, not a finding
    for state in bad.states[last_held + 1:]:
        state["objects"]["cup"][2] -= 0.097
    assert [f.kind for f in physics_findings(bad)] == []


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
    # (and, as written, the milk then jumped from the cup's place into the hand: unheld)
    found = [f for f in physics_findings(bad) if f.kind != "unheld"]
    assert [(f.kind, f.what, f.line) for f in found] == [
        ("support", "milk rests on nothing", first_cup + 2)], found
    assert found[0].value == pytest.approx(top * 100, abs=0.15), found[0].value


def test_a_held_item_away_from_its_fingers_or_in_the_other_hand_is_found(trace) -> None:
    """(A red-team trace carried the cup 50 cm beside the hand, another said the right
    hand held the cup the left one carried: both passed.)"""
    held = _held_states(trace, "cup")
    beside = copy.deepcopy(trace)
    for i in held:
        beside.states[i]["objects"]["cup"][1] += 0.5
    found = [f for f in physics_findings(beside) if f.kind == "hold"]
    assert [f.what.split(",")[0] for f in found] == [
        f"cup held by the {trace.states[held[0]]['held']['cup']} hand"], found
    assert found[0].value == pytest.approx(50, abs=5) and found[0].limit == 3
    assert found[0].line == held[0] + 2
    other = copy.deepcopy(trace)
    for i in held:
        arm = other.states[i]["held"]["cup"]
        other.states[i]["held"]["cup"] = "left" if arm == "right" else "right"
    assert [f.kind for f in physics_findings(other) if f.kind == "hold"] == ["hold"]


def test_a_held_item_heavier_than_a_hand_may_hold_is_found(trace) -> None:
    from dataclasses import replace

    from cramlite.trace.check import checker_for

    checker = checker_for(trace)
    checker.items["cup"] = replace(checker.items["cup"], mass_kg=50.0)
    found = [f for f in physics_findings(trace, checker) if f.kind == "payload"]
    assert [(f.what, f.value, f.limit, f.unit) for f in found] == [
        (f"cup held by the {trace.states[_held_states(trace, 'cup')[0]]['held']['cup']} "
         "hand", 50.0, 1.8, "kg")]


def test_an_item_no_hand_holds_moves_only_by_falling(trace) -> None:
    """(A red-team trace slid a cup nobody held 30 cm along the counter and back.)"""
    first = _held_states(trace, "cup")[0]
    slid = copy.deepcopy(trace)
    for state in slid.states[first // 3:first // 2]:
        state["objects"]["cup"][1] -= 0.3
    found = [f for f in physics_findings(slid) if f.kind == "unheld"]
    assert [(f.what, f.line) for f in found] == [
        ("cup moved with no hand holding it", first // 3 + 2)], found
    assert found[0].value == pytest.approx(30, abs=0.1)
    lifted = copy.deepcopy(trace)  # (5 cm up, nothing lifting it)
    for state in lifted.states[first // 3:first // 2]:
        state["objects"]["cup"][2] += 0.05
    assert [f.kind for f in physics_findings(lifted) if f.kind == "unheld"] == ["unheld"]
    # nor by creeping 9 mm a state, nor in no time, nor at the moment it is let go (a
    # review's forged traces): measured from where it was let go, not step by step
    crept = copy.deepcopy(trace)  # (out and back, 9 mm a state)
    span = crept.states[first // 3:first // 2]
    for n, state in enumerate(span):
        state["objects"]["cup"][1] -= 0.009 * min(n, len(span) - 1 - n)
    assert 0.009 * (len(span) // 2) > 0.1
    assert [f.kind for f in physics_findings(crept) if f.kind == "unheld"] == ["unheld"]
    last = _held_states(trace, "cup")[-1]
    let_go = copy.deepcopy(trace)
    for state in let_go.states[last + 1:]:
        state["objects"]["cup"][0] += 0.25
    found = [f for f in physics_findings(let_go) if f.kind == "unheld"]
    assert [(f.what, f.line) for f in found] == [
        ("cup moved with no hand holding it", last + 3)], found
    taken = copy.deepcopy(trace)  # (picked from 25 cm away: it jumped into the hand)
    for state in taken.states[:first]:
        state["objects"]["cup"][0] += 0.25
    assert [f.what for f in physics_findings(taken) if f.kind == "unheld"] == [
        "cup jumped into the hand"]
    # falling is possible: 20 cm down, 5 cm aside on landing (the support check judges
    # where it comes to rest)
    dropped = copy.deepcopy(trace)
    for state in dropped.states[:first // 3]:
        state["objects"]["cup"][2] += 0.20
        state["objects"]["cup"][0] += 0.05
    assert not [f for f in physics_findings(dropped) if f.kind == "unheld"]


def test_speeds_beyond_the_limits_are_found(trace) -> None:
    """(A red-team trace raised the torso at 0.111 m/s, 12 times its 0.013; the base's
    speed was checked only through its accelerations.)"""
    joints = trace.header["joints"]
    torso = joints.index("torso_lift_joint")
    fast = copy.deepcopy(trace)
    start = fast.states[0]["q"][torso]
    for state in fast.states:
        state["q"][torso] = start + 12 * (state["q"][torso] - start)
    found = [f for f in physics_findings(fast) if f.kind == "joint speed"]
    assert [f.what for f in found] == ["torso_lift_joint"], found
    assert found[0].value > 10 * found[0].limit and found[0].unit == "m/s"
    slow = copy.deepcopy(trace)
    slow.header["base_limits"]["speed_m_s"] = 0.1
    found = [f for f in physics_findings(slow) if f.kind == "base speed"]
    assert [f.what for f in found] == ["driving"] and found[0].limit == 0.1
    assert not [f for f in physics_findings(trace) if "speed" in f.kind]


def test_a_trace_cut_short_is_found_and_an_older_one_is_not_suspected(trace) -> None:
    """A trace's last state is written once more marked "end" when the trial ran to its
    end; without it (interrupted, lines lost) the trace is cut short. A trace from before
    the mark (its header does not promise it) is judged as it was."""
    from cramlite.trace import Trace

    assert trace.header["end_marked"] is True and trace.states[-1]["end"] is True
    assert not trace.cut_short
    cut = Trace(trace.header, trace.states[:len(trace.states) // 2])
    found = physics_findings(cut)
    # (and no acceleration to rest after its last state: it did not stop there)
    assert [(f.kind, f.line) for f in found] == [("cut short", len(cut.states) + 1)], found
    assert "interrupted, or lines were lost" in found[0].describe()
    older = Trace({k: v for k, v in trace.header.items() if k != "end_marked"},
                  trace.states[:-1])
    assert physics_findings(older) == []


def test_an_interrupted_plan_leaves_a_trace_cut_short(tmp_path) -> None:
    plan = tmp_path / "stops.py"
    plan.write_text("from cramlite import ParkArmsAction, MoveTorsoAction\n\n"
                    "def stops(ctx, setup, strategy):\n"
                    "    MoveTorsoAction(0.2).perform(ctx)\n"
                    "    raise KeyboardInterrupt\n")
    path = tmp_path / "stops.jsonl"
    done = run_cli("run", "v1", "--plan", f"{plan}:stops", "--backend", "kinematic",
                   "--trace", str(path))
    assert done.returncode == 130, done.stderr
    checked = run_cli("replay", str(path), "--check")
    assert checked.returncode == 1
    assert "not physical: cut short" in checked.stdout, checked.stdout


@pytest.mark.parametrize(("edit", "expected"), [
    ("drop", "line 4: objects: cup missing (every state lists the objects of the first"),
    ("after", "line 5: a state after the trace's end"),
    ("end", "line 4: end: expected true"),
    ("header", "line 1: header field end_marked: expected true or false, got \"false\"")])
def test_a_state_without_an_object_or_after_the_end_is_malformed(trace, tmp_path, edit,
                                                                 expected) -> None:
    states = copy.deepcopy(trace.states[:3])
    if edit == "drop":
        del states[2]["objects"]["cup"]
    elif edit == "after":
        states[2]["end"] = True
        states.append(copy.deepcopy(trace.states[3]))
    elif edit == "end":
        states[2]["end"] = "yes"
    header = {**trace.header, "end_marked": "false"} if edit == "header" else trace.header
    path = tmp_path / "bad.jsonl"
    path.write_text("\n".join(json.dumps(r) for r in [header, *states]) + "\n")
    done = run_cli("replay", str(path), "--check")
    assert done.returncode == 2 and expected in done.stderr, done.stderr


def test_a_plan_failure_out_of_simulated_robot_leaves_a_whole_trace(tmp_path) -> None:
    """(As a trial's: every state was written; only an interruption or a crash cuts it.)"""
    from cramlite import PickUpAction, simulated_robot
    from cramlite.designators.failures import PlanFailure
    from cramlite.world.setup import load_setup

    path = tmp_path / "failed.jsonl"
    with pytest.raises(PlanFailure), simulated_robot(load_setup("v1"),
                                                     backend="kinematic") as ctx:
        ctx.open_trace(path, "v1", "test", "none", 0, "kinematic")
        PickUpAction("teapot").perform(ctx)
    assert not read_trace(path).cut_short
    crashed = tmp_path / "crashed.jsonl"
    with pytest.raises(RuntimeError), simulated_robot(load_setup("v1"),
                                                      backend="kinematic") as ctx:
        ctx.open_trace(crashed, "v1", "test", "none", 0, "kinematic")
        raise RuntimeError("a bug")
    assert read_trace(crashed).cut_short
