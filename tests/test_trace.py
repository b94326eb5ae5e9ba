"""The trace format (cramlite-trace/1): round trip, validation, replay as GIF and check."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from cramlite.trace import TRACE_FORMAT, TraceError, TraceWriter, read_trace
from cramlite.trace.replay import frame_count
from tests.conftest import ROOT, run_cli

JOINTS = ["torso_lift_joint", "r_shoulder_pan_joint"]
OBJECTS = {"cup": [1.45, 0.85, 0.85, 0.0, 0.0, 0.0, 1.0]}


def header(**extra) -> dict:
    return {"setup": "v1", "plan": "set-table", "strategy": "opm", "seed": 3,
            "joints": JOINTS, "world_joints": [], **extra}


def write(path: Path, states: list[tuple[float, list[float]]]) -> Path:
    writer = TraceWriter(path, header())
    for t, base in states:
        writer.write_state(t, base, [0.25, -1.7], [], {}, OBJECTS, ("NavigateAction", "cup"))
    writer.close()
    return path


def test_round_trip(tmp_path: Path) -> None:
    path = write(tmp_path / "t.jsonl", [(0.0, [-0.5, -1.8, 1.5708]), (0.5, [-0.5, -1.3, 1.5708])])
    lines = path.read_text().splitlines()
    assert json.loads(lines[0]) == {"format": TRACE_FORMAT, **header(), "end_marked": True}
    trace = read_trace(path)
    # (closed: its last state written once more, marked as the end)
    assert trace.header["joints"] == JOINTS and len(trace.states) == 3
    last = {"t": 0.5, "base": [-0.5, -1.3, 1.5708], "q": [0.25, -1.7], "w": [], "held": {},
            "objects": OBJECTS, "action": {"name": "NavigateAction", "object": "cup"}}
    assert trace.states[1:] == [last, {**last, "end": True}]
    assert trace.duration_s == 0.5 and not trace.cut_short


GOOD_STATE = {"t": 0.0, "base": [0, 0, 0], "q": [0.25, -1.7], "w": [], "held": {},
              "objects": OBJECTS, "action": None}


@pytest.mark.parametrize("lines, line, expected", [
    ([], None, "empty file"),
    ([header(format=TRACE_FORMAT)], 2, "no states after the header"),
    (["{not json"], 1, "not valid JSON"),
    ([{"format": "other/1"}], 1, "cramlite-trace/1"),
    ([{"format": TRACE_FORMAT, "setup": "v1"}], 1, "header misses"),
    ([header(format=TRACE_FORMAT), {**GOOD_STATE, "q": [1.0]}], 2, "q: expected 2 numbers"),
    ([header(format=TRACE_FORMAT), {**GOOD_STATE, "t": -1}], 2, "t: expected a time"),
    ([header(format=TRACE_FORMAT), GOOD_STATE, {**GOOD_STATE, "t": 2.0},
      {**GOOD_STATE, "t": 1.0}], 4, "goes back in time"),
    ([header(format=TRACE_FORMAT), {k: v for k, v in GOOD_STATE.items() if k != "held"}], 2,
     "state misses held"),
    ([header(format=TRACE_FORMAT), {**GOOD_STATE, "objects": {"cup": [1, 2]}}], 2,
     "objects: expected"),
    ([header(format=TRACE_FORMAT), {**GOOD_STATE, "base": [0, 0, float("nan")]}], 2,
     "base: expected"),
    ([header(format=TRACE_FORMAT), {**GOOD_STATE, "held": {"cup": "middle"}}], 2,
     "held: expected {object: arm} with arm left or right"),
    ([header(format=TRACE_FORMAT), {**GOOD_STATE, "held": {"plate": "left"}}], 2,
     "held: 'plate' is not one of the state's objects"),
    ([header(format=TRACE_FORMAT), {**GOOD_STATE, "action": {"name": "X", "object": [1]}}],
     2, "action: expected"),
    ([header(format=TRACE_FORMAT), "{\"t\": " + "9" * 5000 + "}"], 2, "not usable JSON"),
    ([header(format=TRACE_FORMAT), "[" * 50_000 + "]" * 50_000], 2, "nested too deeply"),
    ([header(format=TRACE_FORMAT, robot="pr2")], 1, "header field robot: expected"),
    ([header(format=TRACE_FORMAT, robot={"joint_limits": [1]})], 1, "header field robot"),
    ([header(format=TRACE_FORMAT, robot={"joint_limits": {"a": ["a", "b", "c"]}})], 1,
     "header field robot"),
    ([header(format=TRACE_FORMAT, base_limits=[1, 2])], 1, "header field base_limits"),
    ([header(format=TRACE_FORMAT, base_limits={"accel_m_s2": "abc"})], 1,
     "header field base_limits"),
    ([header(format=TRACE_FORMAT, base_limits={"speed_m_s": -1})], 1,
     "header field base_limits"),
    ([header(format=TRACE_FORMAT, joints=[JOINTS[0], JOINTS[0]])], 1,
     "header field joints: 'torso_lift_joint' is listed twice"),
])
def test_malformed_traces_name_the_line(tmp_path: Path, lines, line, expected) -> None:
    path = tmp_path / "bad.jsonl"
    path.write_text("".join((x if isinstance(x, str) else json.dumps(x)) + "\n" for x in lines))
    with pytest.raises(TraceError, match=expected) as info:
        read_trace(path)
    assert info.value.field == (f"line {line}" if line else None)
    result = run_cli("replay", str(path), "--check")
    assert result.returncode == 2
    assert "Traceback" not in result.stderr and len(result.stderr.strip().splitlines()) == 1
    assert str(path) in result.stderr and expected.split(":")[0] in result.stderr


def test_replay_writes_a_gif_with_one_frame_per_tenth_of_robot_time(tmp_path: Path) -> None:
    from PIL import Image

    states = [(0.25 * i, [-0.5, -1.8 + 0.1 * i, math.pi / 2]) for i in range(7)]  # 1.5 s
    path = write(tmp_path / "short.jsonl", states)
    out = tmp_path / "short.gif"
    result = run_cli("replay", str(path), "--out", str(out))
    assert result.returncode == 0, result.stderr
    assert frame_count(1.5, 10, 1) == 16
    with Image.open(out) as gif:
        assert gif.n_frames == 16
        assert gif.info["duration"] == 100
        gif.seek(0)
        first = gif.convert("RGB").tobytes()
        gif.seek(15)
        assert gif.convert("RGB").tobytes() != first  # the robot moved
    fast = tmp_path / "fast.gif"
    assert run_cli("replay", str(path), "--out", str(fast), "--speed", "3").returncode == 0
    with Image.open(fast) as gif:
        assert gif.n_frames == frame_count(1.5, 10, 3) == 6


def test_replay_check_finds_the_robot_inside_the_island(tmp_path: Path) -> None:
    inside = write(tmp_path / "inside.jsonl", [(0.0, [-0.3, 1.3, math.pi]),
                                               (1.0, [-0.9, 1.3, math.pi])])
    result = run_cli("replay", str(inside), "--check")
    print(result.stdout)
    assert result.returncode == 1
    # (depth: how far its deepest point is inside, 34.6 cm below the top and in from the sides)
    assert "base_link 34.6 cm inside island at t = 1.00 s (line 3)" in result.stdout
    clear = write(tmp_path / "clear.jsonl", [(0.0, [-0.2, -1.8, math.pi / 2]),
                                             (2.0, [-0.2, -1.0, math.pi / 2])])  # (0.4 m/s^2)
    result = run_cli("replay", str(clear), "--check")
    assert result.returncode == 0 and "nothing penetrating" in result.stdout


@pytest.mark.parametrize("args, expected", [
    (["--out", "x.png"], "ending in .gif"),
    ([], "say what to do"),
    (["--out", "x.gif", "--fps", "0"], "frames per second > 0"),
    (["--out", "x.gif", "--width", "100000"], "pixels"),
])
def test_replay_bad_options_exit_2(tmp_path: Path, args, expected) -> None:
    path = write(tmp_path / "t.jsonl", [(0.0, [-0.5, -1.8, 0.0])])
    result = run_cli("replay", str(path), *args, cwd=tmp_path)
    assert result.returncode == 2
    assert expected in result.stderr and "Traceback" not in result.stderr


def test_run_writes_a_trace_the_replay_accepts(tmp_path: Path) -> None:
    trace = tmp_path / "v2.jsonl"
    result = run_cli("run", "v2", "--strategy", "opm", "--trace", str(trace), "--json")
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    recorded = read_trace(trace)
    assert recorded.header["setup"] == "v2" and recorded.header["strategy"] == "opm"
    assert recorded.duration_s == pytest.approx(
        data["drive_s"] + data["arm_s"] - data["parallel_s"], rel=0.01)
    assert {"drive_s", "arm_s", "actions"} <= set(data)
    names = {node["name"] for node in data["actions"]}
    assert {"ParkArmsAction", "MoveTorsoAction", "TransportAction"} <= names


@pytest.mark.parametrize("option", ["--trace", "--image"])
def test_run_refuses_a_folder_for_its_trace_or_image_before_running(tmp_path: Path,
                                                                     option: str) -> None:
    folder = tmp_path / ("t.jsonl" if option == "--trace" else "v1.png")
    folder.mkdir()
    result = run_cli("run", "v1", option, str(folder))
    assert result.returncode == 2, result.stdout
    assert "Traceback" not in result.stderr and len(result.stderr.strip().splitlines()) == 1
    assert f"{folder}: {option}: is a folder" in result.stderr
    assert "success" not in result.stdout  # refused before the trial ran


def test_replay_check_finds_an_item_sunk_into_the_counter_or_another_item(
        tmp_path: Path) -> None:
    """Items standing (not in hand) are checked too, wherever they moved."""
    sunk = tmp_path / "sunk.jsonl"
    writer = TraceWriter(sunk, header())
    writer.write_state(0.0, [-0.5, -1.8, 0.0], [0.25, -1.7], [], {},
                       {"cup": [1.45, 0.85, 0.6, 0.0, 0.0, 0.0, 1.0]}, None)
    writer.close()
    result = run_cli("replay", str(sunk), "--check")
    assert result.returncode == 1 and "'cup'" in result.stdout and "counter" in result.stdout


def test_replay_check_says_when_a_contact_is_between_two_states(tmp_path: Path) -> None:
    # both states clear of the island, the straight drive between them through it
    through = write(tmp_path / "through.jsonl", [(0.0, [-0.2, 1.3, math.pi]),
                                                 (2.0, [-2.0, 1.3, math.pi])])
    result = run_cli("replay", str(through), "--check")
    print(result.stdout)
    assert result.returncode == 1
    assert "at t = 1.00 s (between lines 2 and 3)" in result.stdout


def test_replay_refuses_an_output_it_cannot_write_before_rendering(tmp_path: Path) -> None:
    path = write(tmp_path / "t.jsonl", [(0.0, [-0.5, -1.8, 0.0])])
    (tmp_path / "out.gif").mkdir()
    result = run_cli("replay", str(path), "--out", str(tmp_path / "out.gif"))
    assert result.returncode == 2 and "--out: is a folder" in result.stderr
    assert "Traceback" not in result.stderr


def test_a_trace_that_cannot_be_written_is_one_line_naming_it() -> None:
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full here")
    done = run_cli("run", "v1", "--backend", "kinematic", "--trace", "/dev/full")
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr
    assert "/dev/full" in lines[0] and "cannot write the trace" in lines[0]


def test_an_object_the_setup_lacks_is_malformed_and_a_zero_quaternion_a_finding(
        tmp_path: Path) -> None:
    ghost = write(tmp_path / "ghost.jsonl", [(0.0, [-0.5, -1.8, math.pi / 2]),
                                             (1.0, [-0.5, -1.8, math.pi / 2])])
    lines = ghost.read_text().splitlines()
    state = json.loads(lines[2])
    state["objects"]["ghost"] = [0.0, -2.5, 0.5, 0.0, 0.0, 0.0, 1.0]
    ghost.write_text("\n".join([*lines[:2], json.dumps(state)]) + "\n")
    result = run_cli("replay", str(ghost), "--check")
    assert result.returncode == 2 and len(result.stderr.strip().splitlines()) == 1
    assert f"{ghost}: line 3: objects: 'ghost' is not an item of the setup" in result.stderr
    state["objects"] = {"cup": [1.45, 0.85, 0.85, 0.0, 0.0, 0.0, 0.0]}
    ghost.write_text("\n".join([*lines[:2], json.dumps(state)]) + "\n")
    result = run_cli("replay", str(ghost), "--check")
    assert result.returncode == 1 and "quaternion has norm 0" in result.stdout
    assert "Warning" not in result.stderr, result.stderr


def test_run_refuses_to_write_its_trace_over_its_own_setup_or_plan(tmp_path: Path) -> None:
    setup = tmp_path / "mine.yaml"
    setup.write_text((ROOT / "worlds" / "setups" / "v1.yaml").read_text())
    plan = tmp_path / "plan.py"
    plan.write_text("def plan(ctx, setup, strategy):\n    pass\n")
    for trace, what in ((setup, "setup file"), (plan, "plan file")):
        before = trace.read_text()
        done = run_cli("run", str(setup), "--plan", f"{plan}:plan", "--backend", "kinematic",
                       "--trace", str(trace))
        assert done.returncode == 2, done.stderr
        assert f"--trace: is the {what} this command reads" in done.stderr, done.stderr
        assert trace.read_text() == before


def test_a_trace_is_not_checked_against_a_setup_changed_since(tmp_path: Path) -> None:
    setup = tmp_path / "mine.yaml"
    text = (ROOT / "worlds" / "setups" / "v1.yaml").read_text()
    setup.write_text(text)
    trace = tmp_path / "t.jsonl"
    done = run_cli("run", str(setup), "--backend", "kinematic", "--trace", str(trace),
                   "--plan", "set-table", "--order", "cup,milk,bowl,spoon,breakfast-cereal")
    assert done.returncode == 0, done.stderr
    assert run_cli("replay", str(trace), "--check").returncode == 0
    setup.write_text(text.replace("type: cup ", "type: breakfast-cereal ", 1))
    for args in (["--check"], ["--out", str(tmp_path / "t.gif")]):
        changed = run_cli("replay", str(trace), *args)
        assert changed.returncode == 2, changed.stderr
        assert "has changed since this trace was written" in changed.stderr, changed.stderr


def test_a_penetration_under_a_centimetre_is_given_in_millimetres() -> None:
    """`--tolerance-cm 0.01` listed "0.0 cm inside" three times, then "3 deeper than
    0.01 cm": depths under 1 cm are given in mm, to the precision they are found at."""
    from cramlite.trace.check import Penetration

    assert Penetration("island", "bowl", 0.0004, 1.0, 3).describe().startswith(
        "island 0.4 mm inside bowl at t = 1.00 s")
    assert "0.04 mm inside" in Penetration("island", "bowl", 0.00004, 1.0, 3).describe()
    assert "34.6 cm inside" in Penetration("base_link", "island", 0.346, 1.0, 3).describe()


def test_a_door_that_swings_through_a_standing_item_is_found(tmp_path: Path) -> None:
    """A kitchen link and an item were checked only where the item moved (or was held):
    the cupboard door closing through a milk standing just inside it was never looked at
    (a red-team plan closed it there). Now a drawer or door that moves is checked against
    every item."""
    milk = {"milk": [1.28, 1.75, 1.0, 0.0, 0.0, 0.0, 1.0]}  # (its front 0.7 cm past the door)
    writer = TraceWriter(tmp_path / "door.jsonl",
                         {"setup": "c2", "plan": "test", "strategy": "none", "seed": 0,
                          "joints": JOINTS, "world_joints": ["cupboard_door_joint"]})
    for i, t in enumerate((0.0, 0.5, 1.0, 1.5, 2.0)):
        writer.write_state(t, [-0.5, -1.8, 1.5708], [0.0, 0.0], [1.2 * (1 - i / 4)], {}, milk,
                           None)
    writer.close()
    result = run_cli("replay", str(tmp_path / "door.jsonl"), "--check", "--tolerance-cm",
                     "0.3")
    assert result.returncode == 1, result.stdout + result.stderr
    assert "cupboard_door" in result.stdout and "inside 'milk'" in result.stdout, result.stdout
